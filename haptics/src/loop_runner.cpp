#include "haptics/loop_runner.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "realtime/clock.hpp"
#include "realtime/pacing.hpp"

namespace tsmh::haptics {
namespace {}  // namespace

std::string lock_memory() noexcept {
  if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) return "";
  return std::string("mlockall failed (") + std::strerror(errno) +
         "); pages may fault during the loop. Allow it with `ulimit -l unlimited` or "
         "CAP_IPC_LOCK (see docs/haptic-server.md).";
}

CpuDmaLatency::CpuDmaLatency() {
  fd_ = ::open("/dev/cpu_dma_latency", O_RDWR | O_CLOEXEC);
  const std::int32_t zero = 0;
  if (fd_ >= 0 && ::write(fd_, &zero, sizeof zero) == static_cast<ssize_t>(sizeof zero)) return;
  note_ = std::string("cannot hold /dev/cpu_dma_latency at 0 (") + std::strerror(errno) +
          "): CPUs may enter deep idle states and wake the loop late. Run as root or grant write "
          "access to /dev/cpu_dma_latency (docs/haptic-server.md).";
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

CpuDmaLatency::~CpuDmaLatency() {
  if (fd_ >= 0) ::close(fd_);  // closing restores the system's default
}

LoopRunner::LoopRunner(HapticLoop& loop, const RunnerOptions& options)
    : loop_(loop), options_(options) {}

LoopRunner::~LoopRunner() {
  stop();
  join();
}

void LoopRunner::start() {
  thread_ = std::thread([this] { run(); });
  while (!ready_.load(std::memory_order_acquire))
    std::this_thread::yield();
}

void LoopRunner::join() noexcept {
  if (thread_.joinable()) thread_.join();
}

void LoopRunner::run() noexcept {
  if (options_.sched_fifo) {
    sched_param sp{};
    sp.sched_priority = options_.priority;
    const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &sp);
    status_.sched_fifo = rc == 0;
    if (rc != 0)
      status_.sched_note =
          std::string("SCHED_FIFO not permitted (") + std::strerror(rc) +
          "): running at normal priority, expect more jitter. Run as root, or give "
          "the binary CAP_SYS_NICE, or raise RLIMIT_RTPRIO (docs/haptic-server.md).";
  } else {
    status_.sched_note = "SCHED_FIFO disabled by configuration (realtime.sched_fifo: false)";
  }
  if (options_.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(options_.cpu, &set);
    const int rc = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    status_.pinned = rc == 0;
    if (rc != 0) status_.pin_note = std::string("CPU pinning failed: ") + std::strerror(rc);
  }
  ready_.store(true, std::memory_order_release);

  const auto period = static_cast<std::int64_t>(1e9 / options_.rate_hz + 0.5);
  const std::int64_t start = realtime::monotonic_now_ns() + period;
  const std::int64_t end = options_.duration_s > 0
                               ? start + static_cast<std::int64_t>(options_.duration_s * 1e9)
                               : INT64_MAX;
  // Lateness is measured against the absolute schedule (Pacer::due_ns, the
  // first deadline that has not run): after an overrun the schedule re-bases
  // on the next deadline ahead, but the tick that then runs reports how late
  // it is against `due` -- a 100 ms stall reads as 100 ms, not as the few
  // microseconds by which the re-based deadline was missed. The stop flag is
  // checked once per tick, so a signal only ends the sleep early for nothing.
  realtime::Pacer pace(period, start);
  while (!stop_.load(std::memory_order_relaxed) && pace.deadline_ns() < end) {
    pace.wait_through_signals();
    const std::int64_t woke = realtime::monotonic_now_ns();
    loop_.tick(woke, woke - pace.due_ns());
    const std::int64_t done = realtime::monotonic_now_ns();
    loop_.record_compute(done - woke, pace.advance(done));
  }
  loop_.shutdown();
  finished_.store(true, std::memory_order_release);
}

}  // namespace tsmh::haptics
