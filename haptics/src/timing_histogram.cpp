#include "haptics/timing_histogram.hpp"

#include <algorithm>

namespace tsmh::haptics {

void TimingHistogram::record(std::int64_t ns) noexcept {
  if (ns < 0) ns = 0;
  const std::int64_t us = ns / 1000;
  if (us < kBuckets) {
    ++buckets_[static_cast<std::size_t>(us)];
  } else {
    ++overflow_;
  }
  ++count_;
  sum_us_ += static_cast<double>(ns) * 1e-3;
  max_ns_ = std::max(max_ns_, ns);
}

void TimingHistogram::reset() noexcept {
  *this = TimingHistogram{};
}

double TimingHistogram::percentile_us(double q) const noexcept {
  if (count_ == 0) return 0.0;
  const auto target = static_cast<std::uint64_t>(q * static_cast<double>(count_) + 0.5);
  std::uint64_t seen = 0;
  for (int i = 0; i < kBuckets; ++i) {
    seen += buckets_[static_cast<std::size_t>(i)];
    // Upper edge of the bucket, capped by the exact maximum.
    if (seen >= std::max<std::uint64_t>(target, 1)) return std::min(i + 1.0, max_ns_ * 1e-3);
  }
  return max_ns_ * 1e-3;
}

TimingSummary TimingHistogram::summary() const noexcept {
  TimingSummary s;
  s.count = count_;
  if (count_ == 0) return s;
  s.mean_us = sum_us_ / static_cast<double>(count_);
  s.p50_us = percentile_us(0.5);
  s.p99_us = percentile_us(0.99);
  s.p999_us = percentile_us(0.999);
  s.max_us = max_ns_ * 1e-3;
  return s;
}

}  // namespace tsmh::haptics
