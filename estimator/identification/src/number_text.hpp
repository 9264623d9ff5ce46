#pragma once
// Numbers in the estimator's messages and summaries (private to src/).

#include <cstdio>
#include <string>

namespace tsmh::estimator {

/// `v` with `digits` significant digits.
inline std::string num(double v, int digits = 3) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

}  // namespace tsmh::estimator
