#pragma once
// The loop's link to the slave node over LCM: a bridge Receiver (newest
// SLAVE_STATE, and SLAVE_TRUTH when evaluating against the virtual slave)
// and a bridge Sender (MASTER_COMMAND, HAPTIC_STATUS through non-blocking
// outboxes). Construction opens LCM and may throw BridgeError with a fix.
// With a link key, SLAVE_STATE and SLAVE_TRUTH belong to one slave session
// (bridge/link_session.hpp): the server binds to the first slave that
// answers its MASTER_COMMAND, and any other keyed sender there ends the
// session (session_over()); a new slave needs a new server process.
// CALIBRATION_REQUEST may come from any keyed process.

#include <memory>

#include "bridge/inbox.hpp"
#include "bridge/outbox.hpp"
#include "bridge/receiver.hpp"
#include "bridge/sender.hpp"
#include "haptics/slave_link.hpp"
#include "realtime/latest_value.hpp"

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
  bool session_over() const noexcept override {
    return session_ && session_->state() == bridge::SessionState::kFault;
  }
  /// The slave session; null on an unkeyed link.
  const bridge::LinkSession* session() const noexcept { return session_.get(); }
  /// Ends the session deliberately (a clean stop, after the loop's last
  /// tick): the session is closed and the last command is sent once more,
  /// disabled and saying goodbye, so the slave holds and waits for the next
  /// server at once instead of after its timeout. Call it from the thread
  /// that published the commands, or after that thread ended.
  void goodbye() noexcept;
  std::uint64_t latest_calibration_request(bridge::CalibrationRequestSample& out) noexcept override;

  bridge::ChannelStats state_stats() const noexcept { return state_->stats(); }

  /// The last command given to publish_command(), for any thread (0: none
  /// yet), and where and how it goes: what a message prepared outside the
  /// publish thread needs (haptic-server's crash outputs).
  std::uint64_t last_command(bridge::MasterCommandSample& out) const noexcept {
    return last_command_.load(out);
  }
  const std::string& command_channel() const noexcept { return command_->channel(); }
  /// Signs this link's messages; null when the link is not keyed.
  bridge::MessageSigner* signer() noexcept { return tx_.signer(); }

 private:
  bridge::Receiver rx_;
  bridge::Sender tx_;
  std::unique_ptr<bridge::LinkSession> session_;  // declared after tx_: it uses tx_'s signer
  bridge::Inbox<bridge::SlaveStateSample>* state_ = nullptr;
  bridge::Inbox<bridge::SlaveTruthSample>* truth_ = nullptr;
  bridge::Inbox<bridge::CalibrationRequestSample>* calibration_ = nullptr;
  bridge::Outbox<bridge::MasterCommandSample>* command_ = nullptr;
  bridge::Outbox<bridge::HapticStatusSample>* status_ = nullptr;
  realtime::LatestValue<bridge::MasterCommandSample> last_command_;  // loop thread -> main
};

}  // namespace tsmh::haptics
