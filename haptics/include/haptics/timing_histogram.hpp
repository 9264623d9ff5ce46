#pragma once
// Percentiles of loop lateness and compute time, recorded by the loop thread
// itself: 1 us linear buckets up to 20 ms (above that only counted, and max
// kept exactly). Fixed storage; record() never allocates.

#include <array>
#include <cstdint>

namespace tsmh::haptics {

struct TimingSummary {
  std::uint64_t count = 0;
  double mean_us = 0, p50_us = 0, p99_us = 0, p999_us = 0, max_us = 0;
};

class TimingHistogram {
 public:
  static constexpr int kBuckets = 20000;  ///< 1 us each

  void record(std::int64_t ns) noexcept;
  void reset() noexcept;
  TimingSummary summary() const noexcept;
  /// Smallest value v (us) with at least fraction q of the samples <= v.
  double percentile_us(double q) const noexcept;
  std::uint64_t count() const noexcept { return count_; }

 private:
  std::array<std::uint32_t, kBuckets> buckets_{};
  std::uint64_t overflow_ = 0;
  std::uint64_t count_ = 0;
  double sum_us_ = 0.0;
  std::int64_t max_ns_ = 0;
};

}  // namespace tsmh::haptics
