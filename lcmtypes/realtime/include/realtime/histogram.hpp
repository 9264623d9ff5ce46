#pragma once
// Histogram<Buckets>: timing statistics (loop lateness and compute time,
// one-way message latency) recorded by one thread and summarised by any.
// Counters are relaxed atomics written with plain load/store by the single
// writer, so record() is a few moves on x86-64: no allocation, no lock, no
// read-modify-write. Min, max and mean are exact; a percentile is the upper
// edge of its bucket, capped by the exact maximum.
//
// The bucket layout is the only difference between the users, so it is the
// parameter:
//   LinearHistogram  1 us buckets up to 20 ms (above: one overflow bucket):
//                    exact to the microsecond, for the run's loop timing report.
//   LogHistogram     log-linear, 8 buckets per power of two (within 12.5 %)
//                    over the whole int64 range in 496 buckets: cheap to
//                    summarise at 100 Hz (the loop's one-second windows) and
//                    small enough to keep one per channel (bridge latency).

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace tsmh::realtime {

struct HistogramSummary {
  std::uint64_t count = 0;  ///< values recorded
  double min_us = 0;        ///< exact
  double max_us = 0;        ///< exact
  double mean_us = 0;       ///< exact
  double p50_us = 0;        ///< upper edge of the bucket, capped by max_us
  double p99_us = 0;        ///< upper edge of the bucket, capped by max_us
  double p999_us = 0;       ///< upper edge of the bucket, capped by max_us
};

/// `kLinear` 1 us buckets, then one overflow bucket for everything above.
template <int kLinear>
struct LinearBuckets {
  static constexpr int kCount = kLinear + 1;
  static constexpr int index_of(std::uint64_t us) noexcept {
    return us < static_cast<std::uint64_t>(kLinear) ? static_cast<int>(us) : kLinear;
  }
  /// Smallest microsecond value that no longer falls in `bucket`.
  static constexpr std::uint64_t upper_us(int bucket) noexcept {
    return bucket < kLinear ? static_cast<std::uint64_t>(bucket) + 1
                            : std::numeric_limits<std::uint64_t>::max();
  }
};

/// 1 us buckets below 16 us, then 8 per power of two.
struct LogLinearBuckets {
  static constexpr int kCount = 16 + 8 * 60;
  static constexpr int index_of(std::uint64_t us) noexcept {
    if (us < 16) return static_cast<int>(us);
    const int e = std::bit_width(us) - 1;  // floor(log2(us)) >= 4
    const auto sub = static_cast<int>((us >> (e - 3)) & 7U);
    return 16 + (e - 4) * 8 + sub;
  }
  static constexpr std::uint64_t upper_us(int bucket) noexcept {
    if (bucket < 16) return static_cast<std::uint64_t>(bucket) + 1;
    const int e = (bucket - 16) / 8 + 4;
    const auto sub = static_cast<std::uint64_t>((bucket - 16) % 8);
    if (e >= 63) return std::numeric_limits<std::uint64_t>::max();
    return (9 + sub) << (e - 3);
  }
};

template <class Buckets>
class Histogram {
 public:
  static constexpr int kBuckets = Buckets::kCount;

  /// Single writer. Negative values (clock skew) are recorded as 0.
  void record(std::int64_t ns) noexcept {
    if (ns < 0) ns = 0;
    auto& b = buckets_[static_cast<std::size_t>(
        Buckets::index_of(static_cast<std::uint64_t>(ns) / 1000))];
    b.store(b.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    const std::uint64_t n = count_.load(std::memory_order_relaxed);
    if (n == 0 || ns < min_ns_.load(std::memory_order_relaxed))
      min_ns_.store(ns, std::memory_order_relaxed);
    if (n == 0 || ns > max_ns_.load(std::memory_order_relaxed))
      max_ns_.store(ns, std::memory_order_relaxed);
    sum_ns_.store(sum_ns_.load(std::memory_order_relaxed) + ns, std::memory_order_relaxed);
    count_.store(n + 1, std::memory_order_release);
  }

  /// Writer thread only: forget everything (e.g. start a new statistics
  /// window). A concurrent summary() may see a partly cleared histogram.
  void reset() noexcept {
    count_.store(0, std::memory_order_release);
    for (auto& b : buckets_)
      b.store(0, std::memory_order_relaxed);
    sum_ns_.store(0, std::memory_order_relaxed);
    min_ns_.store(0, std::memory_order_relaxed);
    max_ns_.store(0, std::memory_order_relaxed);
  }

  std::uint64_t count() const noexcept { return count_.load(std::memory_order_acquire); }

  /// Any thread; a summary taken during a record() may be off by that one sample.
  HistogramSummary summary() const noexcept {
    HistogramSummary s;
    s.count = count_.load(std::memory_order_acquire);
    if (s.count == 0) return s;
    s.min_us = static_cast<double>(min_ns_.load(std::memory_order_relaxed)) * 1e-3;
    s.max_us = static_cast<double>(max_ns_.load(std::memory_order_relaxed)) * 1e-3;
    s.mean_us = static_cast<double>(sum_ns_.load(std::memory_order_relaxed)) * 1e-3 /
                static_cast<double>(s.count);
    // One pass for the total the ranks refer to (the buckets, not count_: a
    // concurrent record() may have bumped one and not yet the other).
    std::uint64_t total = 0;
    for (const auto& b : buckets_)
      total += b.load(std::memory_order_relaxed);
    s.p50_us = percentile_us(0.50, total, s.max_us);
    s.p99_us = percentile_us(0.99, total, s.max_us);
    s.p999_us = percentile_us(0.999, total, s.max_us);
    return s;
  }

  /// Bucket index of a value in microseconds (exposed for tests).
  static constexpr int bucket_of(std::uint64_t us) noexcept { return Buckets::index_of(us); }
  /// Smallest microsecond value that no longer falls in `bucket`.
  static constexpr std::uint64_t bucket_upper(int bucket) noexcept {
    return Buckets::upper_us(bucket);
  }

 private:
  // Smallest bucket upper edge with at least the nearest-rank share q of the
  // values at or below it, never beyond the exact maximum.
  double percentile_us(double q, std::uint64_t total, double max_us) const noexcept {
    if (total == 0) return max_us;
    const auto rank = static_cast<std::uint64_t>(q * static_cast<double>(total - 1)) + 1;
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < buckets_.size(); ++i) {
      seen += buckets_[i].load(std::memory_order_relaxed);
      if (seen >= rank)
        return std::min(static_cast<double>(Buckets::upper_us(static_cast<int>(i))), max_us);
    }
    return max_us;
  }

  std::array<std::atomic<std::uint64_t>, kBuckets> buckets_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> sum_ns_{0};
  std::atomic<std::int64_t> min_ns_{0};
  std::atomic<std::int64_t> max_ns_{0};
};

/// 1 us resolution up to 20 ms: the loop's whole-run timing report.
using LinearHistogram = Histogram<LinearBuckets<20000>>;
/// Within 12.5 % over any range: per-channel latency, one-second windows.
using LogHistogram = Histogram<LogLinearBuckets>;

}  // namespace tsmh::realtime
