#pragma once
// In-memory stand-ins for the master device and the network, so the loop
// runs in deterministic simulated time.

#include <memory>
#include <vector>

#include "estimator/distal_estimator.hpp"
#include "estimator/tsm_model.hpp"
#include "haptics/slave_link.hpp"
#include "master_devices/device.hpp"

namespace tsmh::haptics::testing {

class FakeDevice final : public master_devices::Device {
 public:
  FakeDevice() {
    spec_.model = "fake";
    spec_.driver = "fake";
    spec_.dof = 2;
    reading_.dof = 2;
    reading_.status = master_devices::DeviceStatus::kOk;
    reading_.buttons.dead_man = true;
  }
  const master_devices::DeviceSpec& spec() const override { return spec_; }
  void open() override {}
  void close() noexcept override {}
  std::string last_error() const override { return {}; }
  bool clear_fault() override { return true; }
  master_devices::DeviceReading read(std::int64_t now_ns) noexcept override {
    reading_.t_ns = now_ns;
    ++reading_.sequence;
    return reading_;
  }
  void write_torque(const master_devices::JointArray& tau) noexcept override {
    torque = tau;
    written.push_back(tau[0]);
    written1.push_back(tau[1]);
  }
  void set_enabled(bool on) noexcept override { enabled = on; }
  void raise_fault(master_devices::FaultCode) noexcept override {}
  master_devices::DeviceStatus status() const noexcept override { return reading_.status; }

  master_devices::DeviceReading reading_;
  master_devices::DeviceSpec spec_;
  master_devices::JointArray torque{};
  std::vector<double> written, written1;
  bool enabled = false;
};

class FakeLink final : public SlaveLink {
 public:
  std::uint64_t latest_state(bridge::SlaveStateSample& out) noexcept override {
    if (version == 0) return 0;
    out = state;
    return version;
  }
  std::uint64_t latest_truth(bridge::SlaveTruthSample& out) noexcept override {
    if (truth_version == 0) return 0;
    out = truth;
    return truth_version;
  }
  void publish_command(const bridge::MasterCommandSample& c) noexcept override {
    commands.push_back(c);
  }
  void publish_status(const bridge::HapticStatusSample& s) noexcept override {
    statuses.push_back(s);
  }
  SlaveLinkStats stats() const noexcept override { return {}; }
  std::uint64_t latest_calibration_request(
      bridge::CalibrationRequestSample& out) noexcept override {
    out = calibration_request;
    return calibration_version;
  }

  /// A new slave sample taken at t_ns and received at the same instant.
  void push(std::int64_t t_ns, double x_in, double t1, double t3, double x_out = 0.0) {
    state.utime = t_ns / 1000;
    state.seq = static_cast<std::int64_t>(version);
    state.receive_ns = t_ns;
    state.num_joints = 2;
    for (int j = 0; j < 2; ++j) {
      state.x_in[j] = x_in;
      state.T1[j] = t1;
      state.T3[j] = t3;
      state.x_out[j] = x_out;
      state.radius_m[j] = 0.01;
    }
    ++version;
  }

  bridge::SlaveStateSample state{};
  bridge::SlaveTruthSample truth{};
  std::uint64_t version = 0, truth_version = 0, calibration_version = 0;
  bridge::CalibrationRequestSample calibration_request{};
  std::vector<bridge::MasterCommandSample> commands;
  std::vector<bridge::HapticStatusSample> statuses;
};

/// One estimator per joint with the paper's model, R = 0.01 m: what the
/// loop tests run unless they test the estimator itself.
inline std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> paper_estimators(
    int joints = 2) {
  std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> v;
  for (int j = 0; j < joints; ++j)
    v.push_back(std::make_unique<estimator::DistalTorqueEstimator>(
        std::make_unique<estimator::TsmFrictionModel>(estimator::paper_spec()), 0.01));
  return v;
}

}  // namespace tsmh::haptics::testing
