#include "haptics/lcm_slave_link.hpp"

namespace tsmh::haptics {

LcmSlaveLink::LcmSlaveLink(const LcmSlaveLinkConfig& config)
    : rx_(config.bridge), tx_(config.bridge) {
  // The server never re-arms: a slave that said goodbye or fell silent is
  // the end of this session (a new slave, a new server process).
  if (bridge::MessageSigner* signer = tx_.signer())
    session_ = std::make_unique<bridge::LinkSession>(*signer, bridge::SessionOptions{});
  bridge::InboxOptions<bridge::SlaveStateSample> state_options;
  state_options.expected_joints = config.joints;
  state_options.limits = config.state_limits;
  state_options.session = session_.get();
  state_ = &rx_.subscribe(state_options);
  if (config.subscribe_truth) {
    bridge::InboxOptions<bridge::SlaveTruthSample> truth_options;
    truth_options.expected_joints = config.joints;
    truth_options.session = session_.get();
    truth_ = &rx_.subscribe(truth_options);
  }
  bridge::InboxOptions<bridge::CalibrationRequestSample> calibration_options;
  calibration_options.expected_joints = config.joints;
  calibration_ = &rx_.subscribe(calibration_options);
  command_ = &tx_.outbox<bridge::MasterCommandSample>();
  status_ = &tx_.outbox<bridge::HapticStatusSample>();
}

LcmSlaveLink::~LcmSlaveLink() {
  stop();
}

void LcmSlaveLink::start() {
  rx_.start();
  tx_.start();
}

void LcmSlaveLink::stop() noexcept {
  tx_.stop();
  rx_.stop();
}

std::uint64_t LcmSlaveLink::latest_state(bridge::SlaveStateSample& out) noexcept {
  return state_->latest(out);
}

std::uint64_t LcmSlaveLink::latest_truth(bridge::SlaveTruthSample& out) noexcept {
  return truth_ ? truth_->latest(out) : 0;
}

std::uint64_t LcmSlaveLink::latest_calibration_request(
    bridge::CalibrationRequestSample& out) noexcept {
  return calibration_->latest(out);
}

void LcmSlaveLink::publish_command(const bridge::MasterCommandSample& cmd) noexcept {
  command_->publish(cmd);
  last_command_.store(cmd);
}

void LcmSlaveLink::goodbye() noexcept {
  if (!session_) return;
  session_->close();
  bridge::MasterCommandSample c;
  last_command_.load(c);
  // After the last one, or the slave drops it (duplicate, time backwards).
  c.seq += 1;
  c.utime += 1;
  c.enable = false;
  c.clutch = false;
  command_->publish(c);
}

void LcmSlaveLink::publish_status(const bridge::HapticStatusSample& status) noexcept {
  status_->publish(status);
}

SlaveLinkStats LcmSlaveLink::stats() const noexcept {
  const auto s = state_->stats();
  return {static_cast<std::int64_t>(s.rejected()), static_cast<std::int64_t>(s.seq_gaps),
          s.latency.p99_us};
}

}  // namespace tsmh::haptics
