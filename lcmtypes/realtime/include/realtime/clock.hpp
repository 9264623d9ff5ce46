#pragma once
// The host's clock for everything that runs in real time: CLOCK_MONOTONIC,
// the clock every message's utime is stamped with (docs/lcm-messages.md) and
// the time base of every master reading. clock_gettime goes through the vDSO,
// so these are safe to call from the 1 kHz loop (no system call, no lock).

#include <time.h>

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

}  // namespace tsmh::realtime
