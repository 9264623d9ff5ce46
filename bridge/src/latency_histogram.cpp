#include "bridge/latency_histogram.hpp"

#include <bit>
#include <limits>

namespace tsmh::bridge {

int LatencyHistogram::bucket_of(std::uint64_t us) noexcept {
  if (us < 16) return static_cast<int>(us);
  const int e = std::bit_width(us) - 1;  // floor(log2(us)) >= 4
  const auto sub = static_cast<int>((us >> (e - 3)) & 7U);
  return 16 + (e - 4) * 8 + sub;
}

std::uint64_t LatencyHistogram::bucket_upper(int bucket) noexcept {
  if (bucket < 16) return static_cast<std::uint64_t>(bucket) + 1;
  const int e = (bucket - 16) / 8 + 4;
  const auto sub = static_cast<std::uint64_t>((bucket - 16) % 8);
  if (e >= 63) return std::numeric_limits<std::uint64_t>::max();
  return (9 + sub) << (e - 3);
}

void LatencyHistogram::record(std::int64_t latency_ns) noexcept {
  if (latency_ns < 0) latency_ns = 0;
  const auto us = static_cast<std::uint64_t>(latency_ns / 1000);
  buckets_[static_cast<std::size_t>(bucket_of(us))].fetch_add(1, std::memory_order_relaxed);
  // Single writer: plain read-modify-write of min/max/sum is race-free.
  const std::uint64_t n = count_.load(std::memory_order_relaxed);
  if (n == 0 || latency_ns < min_ns_.load(std::memory_order_relaxed))
    min_ns_.store(latency_ns, std::memory_order_relaxed);
  if (n == 0 || latency_ns > max_ns_.load(std::memory_order_relaxed))
    max_ns_.store(latency_ns, std::memory_order_relaxed);
  sum_ns_.fetch_add(latency_ns, std::memory_order_relaxed);
  count_.store(n + 1, std::memory_order_release);
}

void LatencyHistogram::reset() noexcept {
  count_.store(0, std::memory_order_release);
  for (auto& b : buckets_)
    b.store(0, std::memory_order_relaxed);
  sum_ns_.store(0, std::memory_order_relaxed);
  min_ns_.store(0, std::memory_order_relaxed);
  max_ns_.store(0, std::memory_order_relaxed);
}

LatencySummary LatencyHistogram::summary() const noexcept {
  LatencySummary s;
  s.count = count_.load(std::memory_order_acquire);
  if (s.count == 0) return s;
  s.min_us = static_cast<double>(min_ns_.load(std::memory_order_relaxed)) * 1e-3;
  s.max_us = static_cast<double>(max_ns_.load(std::memory_order_relaxed)) * 1e-3;
  s.mean_us = static_cast<double>(sum_ns_.load(std::memory_order_relaxed)) * 1e-3 /
              static_cast<double>(s.count);
  std::uint64_t total = 0;
  std::array<std::uint64_t, kBuckets> counts{};
  for (std::size_t i = 0; i < counts.size(); ++i) {
    counts[i] = buckets_[i].load(std::memory_order_relaxed);
    total += counts[i];
  }
  auto percentile = [&](double p) {
    const auto rank = static_cast<std::uint64_t>(p * static_cast<double>(total - 1)) + 1;
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < counts.size(); ++i) {
      seen += counts[i];
      if (seen >= rank) {
        // Upper edge of the bucket, but never beyond the exact maximum.
        const double upper = static_cast<double>(bucket_upper(static_cast<int>(i)));
        return upper < s.max_us ? upper : s.max_us;
      }
    }
    return s.max_us;
  };
  s.p50_us = percentile(0.50);
  s.p99_us = percentile(0.99);
  return s;
}

}  // namespace tsmh::bridge
