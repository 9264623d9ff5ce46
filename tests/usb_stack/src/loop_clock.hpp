#pragma once
// A 1 kHz loop on absolute CLOCK_MONOTONIC deadlines, as the haptic loop
// runs: sleeping to the next deadline never drifts, and the lateness of each
// wake-up is what the host side of the test reports.

#include <time.h>

#include <cstdint>

#include "realtime/clock.hpp"

namespace tsmh::usb_stack {

class LoopClock {
 public:
  explicit LoopClock(std::int64_t period_ns) : period_ns_(period_ns) { rebase(); }

  /// Next deadline starts one period from now (after a phase change or a stall).
  void rebase() { deadline_ = realtime::monotonic_now_ns(); }

  /// Sleeps until the next deadline; returns the wake-up time. A tick more
  /// than ten periods late re-bases instead of bursting to catch up.
  std::int64_t wait() {
    deadline_ += period_ns_;
    realtime::sleep_until_ns(deadline_);
    const std::int64_t now = realtime::monotonic_now_ns();
    lateness_ns_ = now - deadline_;
    if (lateness_ns_ > 10 * period_ns_) deadline_ = now;
    return now;
  }

  std::int64_t lateness_ns() const { return lateness_ns_; }
  std::int64_t period_ns() const { return period_ns_; }

 private:
  std::int64_t period_ns_;
  std::int64_t deadline_ = 0;
  std::int64_t lateness_ns_ = 0;
};

}  // namespace tsmh::usb_stack
