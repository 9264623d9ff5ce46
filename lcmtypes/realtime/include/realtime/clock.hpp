#pragma once
// The project's one clock module.
//
// - CLOCK_MONOTONIC for everything that runs in real time: the loop's
//   deadlines, every message's utime (docs/lcm-messages.md), the time base of
//   every master reading, durations and timeouts. clock_gettime goes through
//   the vDSO, so these are safe to call from the 1 kHz loop (no system call,
//   no lock).
// - CLOCK_REALTIME only where two hosts compare times: the link trailer's
//   send time and its freshness check (bridge/link_auth.hpp), because two
//   hosts' monotonic clocks share no origin. Never for pacing or durations:
//   NTP may step it.
// - Clock: the monotonic clock behind an interface, for components that a
//   test drives in simulated time (the master drivers take one; ManualClock
//   stands still until advanced).
//
// Periodic pacing on these deadlines: realtime/pacing.hpp.

#include <time.h>

#include <atomic>
#include <cstdint>

namespace tsmh::realtime {

/// CLOCK_MONOTONIC now, nanoseconds.
inline std::int64_t monotonic_now_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

/// Sleeps until CLOCK_MONOTONIC reaches deadline_ns (an absolute deadline,
/// so a late wake-up does not shift the ones after it). false: a signal
/// interrupted the sleep before the deadline (callers that must not miss a
/// stop request check it and sleep again).
inline bool sleep_until_ns(std::int64_t deadline_ns) noexcept {
  const timespec ts{static_cast<time_t>(deadline_ns / 1'000'000'000),
                    static_cast<long>(deadline_ns % 1'000'000'000)};
  return clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == 0;
}

/// CLOCK_MONOTONIC now, microseconds: the value to put in a message's utime.
inline std::int64_t monotonic_utime() noexcept {
  return monotonic_now_ns() / 1000;
}

/// CLOCK_REALTIME now, microseconds: only for the link trailer's send time
/// and the receiver's freshness check against it (see above).
inline std::int64_t wall_clock_utime() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000 + ts.tv_nsec / 1000;
}

/// Where a component reads the monotonic time when a test must be able to
/// replace it. Implementations are thread-safe and never block: an I/O
/// thread and the loop read them concurrently.
class Clock {
 public:
  virtual ~Clock() = default;
  /// Now, ns, non-decreasing.
  virtual std::int64_t now_ns() const noexcept = 0;
};

/// The real host clock: monotonic_now_ns().
class MonotonicClock final : public Clock {
 public:
  std::int64_t now_ns() const noexcept override { return monotonic_now_ns(); }
};

/// Simulated time for tests: stands still until advanced. Any thread may
/// read it while another advances it (an atomic).
class ManualClock final : public Clock {
 public:
  /// Starts at `start_ns`; the default is far from 0, as CLOCK_MONOTONIC is
  /// on a running machine, so "time 0" never looks like "no time yet".
  explicit ManualClock(std::int64_t start_ns = 1'000'000'000'000LL) noexcept : now_(start_ns) {}

  std::int64_t now_ns() const noexcept override { return now_.load(std::memory_order_acquire); }
  /// Lets `dt_ns` (>= 0; negative steps are ignored: time never runs back) pass.
  void advance(std::int64_t dt_ns) noexcept {
    if (dt_ns > 0) now_.fetch_add(dt_ns, std::memory_order_acq_rel);
  }

 private:
  std::atomic<std::int64_t> now_;
};

}  // namespace tsmh::realtime
