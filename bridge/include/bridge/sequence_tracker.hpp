#pragma once
// Classifies each (content-valid) message of one channel by its seq and utime
// against the last accepted one: in order, after a gap, duplicate, late
// (reordered), sender restart, or time going backwards. Pure logic, no clock.

#include <cstddef>
#include <cstdint>

namespace tsmh::bridge {

enum class Order : std::uint8_t {
  kFirst,          ///< first message seen: accepted
  kNext,           ///< seq = last + 1: accepted
  kGap,            ///< seq > last + 1: accepted, `missing` numbers skipped
  kRestart,        ///< seq went down but utime went up: the sender restarted, accepted
  kResync,         ///< accepted after `resync_after` consecutive late/backwards drops
  kDuplicate,      ///< seq = last: dropped (a stuck sender must not look fresh)
  kLate,           ///< seq < last and utime not newer: reordered, dropped
  kTimeBackwards,  ///< seq > last but utime <= last: dropped (rejected)
};
inline constexpr std::size_t kOrders = static_cast<std::size_t>(Order::kTimeBackwards) + 1;

struct OrderVerdict {
  Order order = Order::kFirst;
  std::int64_t missing = 0;  ///< sequence numbers skipped (Gap only)
  constexpr bool accepted() const noexcept {
    return order == Order::kFirst || order == Order::kNext || order == Order::kGap ||
           order == Order::kRestart || order == Order::kResync;
  }
};

class SequenceTracker {
 public:
  /// After `resync_after` consecutive Late/TimeBackwards drops the tracker
  /// assumes its reference is bad (one bogus seq/utime would otherwise block a
  /// channel forever) and accepts the next such message as a new start.
  explicit SequenceTracker(int resync_after = 50) noexcept : resync_after_(resync_after) {}

  /// Classifies the message and, when it is accepted, makes it the reference.
  OrderVerdict observe(std::int64_t seq, std::int64_t utime) noexcept;

  std::int64_t last_seq() const noexcept { return last_seq_; }
  std::int64_t last_utime() const noexcept { return last_utime_; }

 private:
  int resync_after_;
  bool has_last_ = false;
  std::int64_t last_seq_ = 0;
  std::int64_t last_utime_ = 0;
  int consecutive_out_of_order_ = 0;
};

}  // namespace tsmh::bridge
