#pragma once
// The host's time as the drivers read it: CLOCK_MONOTONIC in nanoseconds, the
// time base of every DeviceReading.
//
// Drivers and transports do not call realtime::monotonic_now_ns() themselves
// (the one CLOCK_MONOTONIC reading of the project, realtime/clock.hpp): they read a
// Clock given to their constructor (MonotonicClock by default), so a test can
// give them a ManualClock and let time pass by advancing it instead of
// sleeping. Both the driver's I/O thread and the real-time loop read it:
// now_ns() is lock-free and never blocks.

#include <atomic>
#include <cstdint>
#include <memory>

#include "realtime/clock.hpp"

namespace tsmh::master_devices {

/// Where a driver reads the host's time. Implementations are thread-safe
/// and never block: the I/O thread and the loop read them concurrently.
class Clock {
 public:
  virtual ~Clock() = default;
  /// Now, ns, non-decreasing.
  virtual std::int64_t now_ns() const noexcept = 0;
};

/// The real host clock (CLOCK_MONOTONIC): what every driver uses unless told otherwise.
class MonotonicClock final : public Clock {
 public:
  std::int64_t now_ns() const noexcept override { return realtime::monotonic_now_ns(); }
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

/// The default for a driver's clock parameter.
inline std::shared_ptr<const Clock> monotonic_clock() {
  return std::make_shared<MonotonicClock>();
}

}  // namespace tsmh::master_devices
