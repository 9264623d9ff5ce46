#pragma once
// The one quantile rule of the estimator (thresholds, plateaus, noise levels
// read off recordings). Every quantile and median in estimator code goes
// through here so that a threshold documented as "the 95th percentile of the
// speed" means the same sample everywhere.
//
// Rule: the q-quantile of n samples is the sample of 0-based rank
// floor(q * (n - 1)) in ascending order (numpy's method="lower"). It is
// always one of the samples, never an interpolation, so a threshold taken
// from a recording is a value the recording holds. The median is
// quantile(v, 0.5): for an even count it is the lower of the two middle
// samples.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace tsmh::estimator {

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

}  // namespace tsmh::estimator
