#pragma once
// Runs a HapticLoop on its own thread against absolute deadlines on
// CLOCK_MONOTONIC (clock_nanosleep TIMER_ABSTIME): no drift, re-base and skip
// on overrun (realtime/pacing.hpp). Tries SCHED_FIFO and says clearly when it
// is not permitted; the loop then runs at normal priority.

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>

#include "haptics/haptic_loop.hpp"

namespace tsmh::haptics {

struct RunnerOptions {
  double rate_hz = 1000.0;
  bool sched_fifo = true;
  int priority = 80;
  int cpu = -1;
  double duration_s = 0.0;  ///< 0: until stop()
};

/// What the runner could get from the OS, for the start-up message.
struct RealtimeStatus {
  bool sched_fifo = false;
  std::string sched_note;  ///< why not, and how to allow it
  bool pinned = false;
  std::string pin_note;
};

class LoopRunner {
 public:
  LoopRunner(HapticLoop& loop, const RunnerOptions& options);
  ~LoopRunner();
  LoopRunner(const LoopRunner&) = delete;
  LoopRunner& operator=(const LoopRunner&) = delete;

  /// Starts the loop thread; returns once it has applied its scheduling
  /// (so status() is meaningful).
  void start();
  /// Asks the loop to stop; join() waits. The loop thread calls
  /// HapticLoop::shutdown() (zero torque) before it exits.
  void stop() noexcept { stop_.store(true, std::memory_order_relaxed); }
  void join() noexcept;
  bool finished() const noexcept { return finished_.load(std::memory_order_acquire); }
  const RealtimeStatus& status() const noexcept { return status_; }

 private:
  void run() noexcept;

  HapticLoop& loop_;
  RunnerOptions options_;
  RealtimeStatus status_;
  std::atomic<bool> stop_{false};
  std::atomic<bool> finished_{false};
  std::atomic<bool> ready_{false};
  std::thread thread_;
};

/// mlockall(MCL_CURRENT | MCL_FUTURE); returns "" on success, else why not.
std::string lock_memory() noexcept;

/// Holds /dev/cpu_dma_latency at 0 us while it lives (the PM QoS interface):
/// idle CPUs stay out of deep C-states, so a timer wake-up is not delayed by
/// their exit latency. On this project's 2-core VM it takes loop lateness
/// from p50 46 / p99 71 us to p50 16 / p99 31 us (docs/haptic-server.md).
class CpuDmaLatency {
 public:
  CpuDmaLatency();
  ~CpuDmaLatency();
  CpuDmaLatency(const CpuDmaLatency&) = delete;
  CpuDmaLatency& operator=(const CpuDmaLatency&) = delete;
  bool active() const noexcept { return fd_ >= 0; }
  const std::string& note() const noexcept { return note_; }  ///< why not, when inactive

 private:
  int fd_ = -1;
  std::string note_;
};

}  // namespace tsmh::haptics
