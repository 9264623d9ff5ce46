#pragma once
// The one quantile rule of the project: estimator thresholds read off
// recordings (the 95th percentile of the speed, the median friction), the
// benchmarks' and test programs' percentiles (p50, p99, p99.9 of a latency),
// and the accuracy harness's medians all go through here, so "the 99th
// percentile" means the same sample everywhere.
//
// Rule: the q-quantile of n samples is the sample of 0-based rank
// floor(q * (n - 1)) in ascending order (numpy's method="lower"). It is
// always one of the samples, never an interpolation, so a threshold taken
// from a recording is a value the recording holds and a reported latency is
// one that happened. The median is quantile(v, 0.5): for an even count it is
// the lower of the two middle samples.
//
// (The timing histograms' percentile_us, realtime/histogram.hpp, reads a
// bucket bound, not a sample: it is a bounded summary of a stream too long
// to keep, with its own stated resolution.)

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numeric>
#include <utility>
#include <vector>

namespace tsmh::realtime {

/// The q-quantile (q in [0, 1], clamped) of `v` by the rule above; NaN for
/// an empty set or a NaN q. Takes a copy because it partially reorders it.
inline double quantile(std::vector<double> v, double q) {
  if (v.empty() || std::isnan(q)) return std::nan("");
  const double qc = std::clamp(q, 0.0, 1.0);
  const auto k = static_cast<std::size_t>(qc * static_cast<double>(v.size() - 1));
  const auto kth = v.begin() + static_cast<std::ptrdiff_t>(k);
  std::nth_element(v.begin(), kth, v.end());
  return *kth;
}

/// quantile(v, 0.5): the lower middle sample for an even count.
inline double median(std::vector<double> v) {
  return quantile(std::move(v), 0.5);
}

/// The summary the benchmarks print: percentiles by the rule above, the
/// largest and the mean. All NaN (count 0) for an empty set.
struct Percentiles {
  double p50 = std::nan("");
  double p90 = std::nan("");
  double p99 = std::nan("");
  double p999 = std::nan("");
  double max = std::nan("");
  double mean = std::nan("");
  std::size_t count = 0;
};

inline Percentiles percentiles(std::vector<double> v) {
  Percentiles p;
  p.count = v.size();
  if (v.empty()) return p;
  std::sort(v.begin(), v.end());
  const auto at = [&](double q) {
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
  };
  p.p50 = at(0.5);
  p.p90 = at(0.9);
  p.p99 = at(0.99);
  p.p999 = at(0.999);
  p.max = v.back();
  p.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  return p;
}

}  // namespace tsmh::realtime
