#pragma once
// The one pacing loop of the project: a periodic schedule of absolute
// deadlines on CLOCK_MONOTONIC (after SAI's LoopTimer), used by haptic-server's
// loop, the bridge's polling sender, the simulated and emulated consoles and
// the example programs. Deadlines are k * period after the first, never "sleep
// for a period" (which drifts). When a tick overruns past the next deadline,
// the schedule re-bases on the first deadline still ahead and counts the
// skipped ticks, instead of running a burst of late ticks to catch up: a
// stalled loop resumes at its rate, and the caller knows what it missed.
// Only a stand-in for hardware (the emulated console bus) runs every period
// instead (Pacer::advance_every).

#include <cstdint>

#include "realtime/clock.hpp"

namespace tsmh::realtime {

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

/// The schedule and its sleep. Use:
///   Pacer pace(period_ns, monotonic_now_ns() + period_ns);
///   while (running) {
///     if (!pace.wait()) continue;       // a signal: check the stop request
///     ... one tick, late by monotonic_now_ns() - pace.due_ns() ...
///     skipped += pace.advance(monotonic_now_ns());
///   }
class Pacer {
 public:
  /// `period_ns` > 0; the first deadline at `first_deadline_ns`.
  constexpr Pacer(std::int64_t period_ns, std::int64_t first_deadline_ns) noexcept
      : period_(period_ns), deadline_(first_deadline_ns), due_(first_deadline_ns) {}

  /// Sleeps until deadline_ns(). false: a signal ended the sleep early; the
  /// schedule is unchanged (check any stop request, then wait again).
  bool wait() const noexcept { return sleep_until_ns(deadline_); }
  /// As wait(), but sleeps on through signals.
  void wait_through_signals() const noexcept {
    while (!sleep_until_ns(deadline_)) {
    }
  }
  /// The tick due at deadline_ns() finished at `done_ns`: moves to the next
  /// deadline still ahead of it. Returns the deadlines skipped.
  constexpr std::int64_t advance(std::int64_t done_ns) noexcept {
    const NextTick n = next_tick(deadline_, done_ns, period_);
    deadline_ = n.deadline_ns;
    due_ = n.due_ns;
    return n.skipped;
  }

  /// For a stand-in for hardware whose every period counts (an emulated
  /// device's reports, which a real device sends on its own clock and the
  /// kernel queues): the next deadline is the one after this whatever the
  /// time, so a stall is followed by the missed ticks back to back.
  constexpr void advance_every() noexcept {
    deadline_ += period_;
    due_ = deadline_;
  }

  /// The deadline the next wait() sleeps to.
  constexpr std::int64_t deadline_ns() const noexcept { return deadline_; }
  /// The first deadline that has not run: what the next tick's lateness is
  /// measured against (earlier than deadline_ns() after a skip).
  constexpr std::int64_t due_ns() const noexcept { return due_; }
  constexpr std::int64_t period_ns() const noexcept { return period_; }

 private:
  std::int64_t period_;
  std::int64_t deadline_;
  std::int64_t due_;
};

}  // namespace tsmh::realtime
