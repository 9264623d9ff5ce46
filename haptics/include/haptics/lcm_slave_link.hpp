#pragma once
// The loop's link to the slave node over LCM: a bridge Receiver (newest
// SLAVE_STATE, and SLAVE_TRUTH when evaluating against the virtual slave)
// and a bridge Sender (MASTER_COMMAND, HAPTIC_STATUS through non-blocking
// outboxes). Construction opens LCM and may throw BridgeError with a fix.

#include <memory>

#include "bridge/inbox.hpp"
#include "bridge/outbox.hpp"
#include "bridge/receiver.hpp"
#include "bridge/sender.hpp"
#include "haptics/slave_link.hpp"

namespace tsmh::haptics {

struct LcmSlaveLinkConfig {
  bridge::BridgeConfig bridge;
  int joints = 2;
  bridge::SlaveStateLimits state_limits{};  ///< ranges and plausible steps of SLAVE_STATE
  bool subscribe_truth = false;             ///< evaluation against the virtual slave
};

class LcmSlaveLink final : public SlaveLink {
 public:
  explicit LcmSlaveLink(const LcmSlaveLinkConfig& config);
  ~LcmSlaveLink() override;

  /// Starts the receive and publish threads.
  void start();
  /// Stops them after flushing queued messages (also done by the destructor).
  void stop() noexcept;

  std::uint64_t latest_state(bridge::SlaveStateSample& out) noexcept override;
  std::uint64_t latest_truth(bridge::SlaveTruthSample& out) noexcept override;
  void publish_command(const bridge::MasterCommandSample& cmd) noexcept override;
  void publish_status(const bridge::HapticStatusSample& status) noexcept override;
  SlaveLinkStats stats() const noexcept override;
  std::uint64_t latest_calibration_request(bridge::CalibrationRequestSample& out) noexcept override;

  bridge::ChannelStats state_stats() const noexcept { return state_->stats(); }

 private:
  bridge::Receiver rx_;
  bridge::Sender tx_;
  bridge::Inbox<bridge::SlaveStateSample>* state_ = nullptr;
  bridge::Inbox<bridge::SlaveTruthSample>* truth_ = nullptr;
  bridge::Inbox<bridge::CalibrationRequestSample>* calibration_ = nullptr;
  bridge::Outbox<bridge::MasterCommandSample>* command_ = nullptr;
  bridge::Outbox<bridge::HapticStatusSample>* status_ = nullptr;
};

}  // namespace tsmh::haptics
