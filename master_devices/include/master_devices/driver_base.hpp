#pragma once
// What every driver here shares, written once: the spec, the host's enable
// request, the latched fault, the error text, the two cells between the loop
// and the driver's I/O side (readings in, torque commands out), and the
// Device overrides built on them. A driver derives from DriverBase, fills
// spec_ in its constructor, and writes only what its device needs: open(),
// close(), how old a reading may be (freshness_bound_ns()) and its I/O side,
// which asks torque_to_send() what to put on the wire; clear_fault() and
// read() only when its device needs more than the shared ones.
//
// The safety rules therefore hold for every driver alike: a fault latches
// (the first cause is the one reported) and turns the enable request off;
// torque goes out only while the device is OK, enabled and the newest
// command is younger than the driver's command timeout, clamped to the
// spec's peak, with NaN as zero; a stale reading is kDisconnected with
// nothing commanded (apply_reading_rules).

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

#include "master_devices/clock.hpp"
#include "master_devices/device.hpp"
#include "realtime/joint_names.hpp"
#include "realtime/latest_value.hpp"

namespace tsmh::master_devices {

class DriverBase : public Device {
 public:
  const DeviceSpec& spec() const override { return spec_; }
  /// The error recorded last; with none recorded while faulted, the fault in
  /// words ("fault raised by the host", "fault: workspace").
  std::string last_error() const override;

  /// Stores the command with the clock's time; the I/O side limits it
  /// (torque_to_send) when it sends.
  void write_torque(const JointArray& tau_nm) noexcept override;
  void set_enabled(bool on) noexcept override { enable_requested_.store(on); }
  void raise_fault(FaultCode code) noexcept override { latch_fault(code); }
  /// Unlatches the fault and forgets the error; torque stays off until
  /// set_enabled(true). A driver whose device must be told, or whose cause
  /// must be checked first, overrides it.
  bool clear_fault() override;
  /// The loop's read(): newest_reading() with the driver's freshness bound.
  DeviceReading read(std::int64_t now_ns) noexcept override {
    return newest_reading(now_ns, freshness_bound_ns());
  }
  /// read() says kDisconnected (stale) when the newest reading is older than
  /// this, ns.
  virtual std::int64_t freshness_bound_ns() const noexcept = 0;
  /// kClosed until open(), kFault while a fault is latched, kDisconnected
  /// while the link is down, else kOk.
  DeviceStatus status() const noexcept override;

 protected:
  explicit DriverBase(std::shared_ptr<const Clock> clock);

  struct Command {
    JointArray tau{};
    std::int64_t t_ns = 0;
    bool valid = false;  ///< false until the first write_torque()
  };
  struct Torque {
    JointArray tau{};    ///< what to send: limited, zero unless `drive`
    bool drive = false;  ///< torque output on
  };

  /// Latches `code` unless a fault is latched already, and turns the enable
  /// request off. True when this call latched it. Any thread, lock-free.
  bool latch_fault(FaultCode code) noexcept;
  /// Clears the latched fault; torque stays off until set_enabled(true).
  void unlatch_fault() noexcept;
  FaultCode fault() const noexcept { return fault_.load(); }
  bool enable_requested() const noexcept { return enable_requested_.load(); }

  /// What the I/O side sends for `cmd` at `now_ns`: the command clamped to
  /// spec_.peak_torque_nm (NaN as 0) when `allowed` by the driver's own
  /// checks, the device is OK and enabled, and the command is at most
  /// `command_timeout_ns` old; zero otherwise.
  Torque torque_to_send(const Command& cmd, std::int64_t now_ns, std::int64_t command_timeout_ns,
                        bool allowed = true) const noexcept;

  /// The loop's read(): the newest reading from readings_ with this
  /// device's status and fault, and the shared reading rules for a freshness
  /// bound of `fresh_bound_ns` (types.hpp).
  DeviceReading newest_reading(std::int64_t now_ns, std::int64_t fresh_bound_ns) noexcept;

  void set_error(const std::string& text);

  DeviceSpec spec_;
  std::shared_ptr<const Clock> clock_;  ///< stamps commands (and what the driver dates)
  std::atomic<bool> opened_{false};
  std::atomic<bool> link_up_{false};
  realtime::LatestValue<DeviceReading> readings_;  ///< I/O side -> loop
  realtime::LatestValue<Command> commands_;        ///< loop -> I/O side
  /// Guards error_; the I/O side may take it, the loop never does.
  mutable std::mutex error_mutex_;
  std::string error_;

 private:
  realtime::LatestValueReader<DeviceReading> reading_reader_{readings_};  // the loop's
  std::atomic<bool> enable_requested_{false};
  std::atomic<FaultCode> fault_{FaultCode::kNone};
};

/// Copies a driver's per-joint limits (settings with peak_torque_nm,
/// continuous_torque_nm, position_min_rad, position_max_rad and
/// max_stiffness_nm_per_rad) into `spec` for joints 0 .. spec.dof-1, naming
/// them as the rest of the project does: joint1, joint2, ... (realtime/joint_names.hpp).
template <class JointLimits>
void copy_joint_limits(const JointLimits& s, DeviceSpec& spec) {
  for (std::size_t j = 0; j < spec.dof; ++j) {
    spec.joint_names[j] = realtime::joint_name(j);
    spec.peak_torque_nm[j] = s.peak_torque_nm[j];
    spec.max_continuous_torque_nm[j] = s.continuous_torque_nm[j];
    spec.position_min_rad[j] = s.position_min_rad[j];
    spec.position_max_rad[j] = s.position_max_rad[j];
    spec.max_stiffness_nm_per_rad[j] = s.max_stiffness_nm_per_rad[j];
  }
}

}  // namespace tsmh::master_devices
