#pragma once
// Absolute-deadline scheduling of a periodic loop (after SAI's LoopTimer):
// deadlines are k * period after the start on CLOCK_MONOTONIC, never "sleep
// for a period" (which drifts). When a tick overruns past the next deadline,
// the schedule re-bases on the first deadline still ahead and counts the
// skipped ticks, instead of running a burst of late ticks to catch up.

#include <cstdint>

namespace tsmh::haptics {

struct NextTick {
  std::int64_t deadline_ns;  ///< the next deadline, strictly after `now`
  std::int64_t skipped;      ///< deadlines that were missed and will not run
  /// The first deadline that has not run: the next tick's lateness is
  /// measured against it, so a stall is never hidden by the re-basing
  /// (equal to deadline_ns when nothing was skipped).
  std::int64_t due_ns;
};

/// The deadline after `deadline_ns` given the time `now_ns` when the tick
/// finished. Pure: the clock is the caller's.
constexpr NextTick next_tick(std::int64_t deadline_ns, std::int64_t now_ns,
                             std::int64_t period_ns) noexcept {
  const std::int64_t next = deadline_ns + period_ns;
  if (now_ns < next) return {next, 0, next};
  const std::int64_t missed = (now_ns - next) / period_ns + 1;
  return {next + missed * period_ns, missed, next};
}

}  // namespace tsmh::haptics
