#pragma once
// What the loop needs of the network, as an interface so the loop logic runs
// in deterministic simulated time in tests (an in-memory link) and over LCM
// in the server (LcmSlaveLink). Every call is made from the loop thread and
// must never block, allocate or lock.

#include <cstdint>

#include "bridge/samples.hpp"

namespace tsmh::haptics {

struct SlaveLinkStats {
  std::int64_t rejected = 0;    ///< incoming SLAVE_STATE messages refused by validation
  std::int64_t seq_gaps = 0;    ///< SLAVE_STATE sequence numbers missed
  double latency_p99_us = 0.0;  ///< one-way latency of SLAVE_STATE (same host)
};

class SlaveLink {
 public:
  virtual ~SlaveLink() = default;
  /// Newest accepted SLAVE_STATE; returns its version (+1 per new sample), 0 when none yet.
  virtual std::uint64_t latest_state(bridge::SlaveStateSample& out) noexcept = 0;
  /// Newest SLAVE_TRUTH (virtual slave only, for evaluation); 0 when none or not subscribed.
  virtual std::uint64_t latest_truth(bridge::SlaveTruthSample& out) noexcept = 0;
  virtual void publish_command(const bridge::MasterCommandSample& cmd) noexcept = 0;
  virtual void publish_status(const bridge::HapticStatusSample& status) noexcept = 0;
  virtual SlaveLinkStats stats() const noexcept = 0;
  /// The slave session ended for good: another keyed sender appeared on
  /// SLAVE_STATE (bridge/link_session.hpp). Unkeyed links have no session.
  virtual bool session_over() const noexcept { return false; }
  /// Newest CALIBRATION_REQUEST (an external console asks for a
  /// recalibration); its version, 0 when none. Links without one never ask.
  virtual std::uint64_t latest_calibration_request(
      bridge::CalibrationRequestSample& /*out*/) noexcept {
    return 0;
  }
};

}  // namespace tsmh::haptics
