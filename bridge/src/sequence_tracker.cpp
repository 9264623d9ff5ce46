#include "bridge/sequence_tracker.hpp"

namespace tsmh::bridge {

OrderVerdict SequenceTracker::observe(std::int64_t seq, std::int64_t utime) noexcept {
  OrderVerdict v;
  if (!has_last_) {
    v.order = Order::kFirst;
  } else if (seq == last_seq_) {
    // Not counted towards a resync: a sender repeating itself must not be
    // taken for a fresh one.
    v.order = Order::kDuplicate;
    return v;
  } else if (seq > last_seq_) {
    // The distance in unsigned arithmetic: seq - last_seq_ overflows int64
    // when a hostile sender puts INT64_MAX after a negative seq.
    const std::uint64_t ahead =
        static_cast<std::uint64_t>(seq) - static_cast<std::uint64_t>(last_seq_);
    if (utime <= last_utime_) {
      v.order = Order::kTimeBackwards;
    } else if (ahead == 1) {
      v.order = Order::kNext;
    } else {
      v.order = Order::kGap;
      constexpr auto kMax = static_cast<std::uint64_t>(INT64_MAX);
      v.missing = static_cast<std::int64_t>(ahead - 1 > kMax ? kMax : ahead - 1);
    }
  } else {
    v.order = utime > last_utime_ ? Order::kRestart : Order::kLate;
  }

  if (!v.accepted()) {
    if (++consecutive_out_of_order_ < resync_after_) return v;
    v.order = Order::kResync;
    v.missing = 0;
  }
  consecutive_out_of_order_ = 0;
  has_last_ = true;
  last_seq_ = seq;
  last_utime_ = utime;
  return v;
}

}  // namespace tsmh::bridge
