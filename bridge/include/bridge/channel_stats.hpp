#pragma once
// Counters of one incoming channel, as a plain snapshot.

#include <array>
#include <cstdint>
#include <numeric>

#include "bridge/rejection.hpp"
#include "realtime/histogram.hpp"

namespace tsmh::bridge {

struct ChannelStats {
  std::uint64_t received = 0;  ///< every message that arrived on the channel
  std::uint64_t accepted = 0;  ///< handed to the loop
  /// Rejected messages by RejectReason (index = static_cast<int>(reason)).
  std::array<std::uint64_t, kRejectReasons> rejected_by{};
  /// Authentic messages of a session's handshake (a hello, or the peer's
  /// before it heard our answer): not rejected, but their content is not used.
  std::uint64_t handshake = 0;
  std::uint64_t duplicates = 0;  ///< seq equal to the last accepted: dropped
  std::uint64_t reordered = 0;   ///< arrived after a newer one: dropped
  /// Gaps between accepted messages (lost or rejected in between): one per
  /// event, however many numbers it skipped.
  std::uint64_t seq_gaps = 0;
  /// Sequence numbers those gaps skipped, saturating at UINT64_MAX (a hostile
  /// seq can claim 2^63 missing messages in one go).
  std::uint64_t seq_missing = 0;
  std::uint64_t restarts = 0;  ///< sender restarts detected (seq down, utime up)
  std::uint64_t resyncs = 0;   ///< tracker re-based after a run of out-of-order messages
  /// Queued between subscribe() and Receiver::start() and dropped unread (not
  /// in `received`): they were old before anyone looked, and would otherwise
  /// read as a burst of huge latencies and a gap at start.
  std::uint64_t discarded_before_start = 0;
  realtime::HistogramSummary
      latency;                       ///< receive time - utime, accepted messages, shared clock only
  std::int64_t last_receive_ns = 0;  ///< CLOCK_MONOTONIC of the newest accepted message, 0 if none

  std::uint64_t rejected(RejectReason r) const noexcept {
    return rejected_by[static_cast<std::size_t>(r)];
  }
  std::uint64_t rejected() const noexcept {
    return std::accumulate(rejected_by.begin(), rejected_by.end(), std::uint64_t{0});
  }
  /// Everything that never reached the loop.
  std::uint64_t dropped() const noexcept { return rejected() + handshake + duplicates + reordered; }
};

}  // namespace tsmh::bridge
