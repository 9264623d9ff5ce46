#pragma once
// Percentiles of a sample set, for the METRIC lines of the guest programs.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace tsmh::usb_stack {

struct Percentiles {
  double p50 = 0.0;
  double p99 = 0.0;
  double p999 = 0.0;
  double max = 0.0;
  std::size_t count = 0;
};

/// Nearest-rank percentiles; all zero for an empty set. Takes a copy to sort.
inline Percentiles percentiles(std::vector<double> v) {
  Percentiles p;
  p.count = v.size();
  if (v.empty()) return p;
  std::sort(v.begin(), v.end());
  const auto rank = [&](double q) {
    const auto i = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
    return v[std::min(v.size() - 1, i == 0 ? 0 : i - 1)];
  };
  p.p50 = rank(0.50);
  p.p99 = rank(0.99);
  p.p999 = rank(0.999);
  p.max = v.back();
  return p;
}

}  // namespace tsmh::usb_stack
