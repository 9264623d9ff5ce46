#pragma once
// One-way latency statistics kept by the receive thread (single writer) and
// read by anyone. Log-linear buckets (8 per power of two, so a percentile is
// within 12.5 %) in relaxed atomics: recording never allocates or locks.

#include <array>
#include <atomic>
#include <cstdint>

namespace tsmh::bridge {

struct LatencySummary {
  std::uint64_t count = 0;  ///< latencies recorded
  double min_us = 0;        ///< exact
  double max_us = 0;        ///< exact
  double mean_us = 0;       ///< exact
  double p50_us = 0;        ///< bucket estimate (upper edge, within 12.5 %)
  double p99_us = 0;        ///< bucket estimate (upper edge, within 12.5 %)
};

class LatencyHistogram {
 public:
  /// Single writer. Negative values (clock skew) are recorded as 0.
  void record(std::int64_t latency_ns) noexcept;
  /// Any thread; a summary taken during a record() may be off by that one sample.
  LatencySummary summary() const noexcept;
  /// Writer thread only: forget everything (e.g. start a new statistics
  /// window). A concurrent summary() may see a partly cleared histogram.
  void reset() noexcept;

  /// Bucket index of a latency in microseconds (exposed for tests).
  static int bucket_of(std::uint64_t us) noexcept;
  /// Smallest microsecond value that no longer falls in `bucket`.
  static std::uint64_t bucket_upper(int bucket) noexcept;
  static constexpr int kBuckets = 16 + 8 * 60;

 private:
  std::array<std::atomic<std::uint64_t>, kBuckets> buckets_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::int64_t> sum_ns_{0};
  std::atomic<std::int64_t> min_ns_{0};
  std::atomic<std::int64_t> max_ns_{0};
};

}  // namespace tsmh::bridge
