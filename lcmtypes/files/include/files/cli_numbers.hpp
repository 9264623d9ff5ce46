#pragma once
// Numbers given on a command line are input too: `--duration nan` ran
// forever and `--duration 1e10` ended at once (it overflowed a nanosecond
// count), and CLI11's own Range() lets NaN through (both comparisons are
// false). finite_range() refuses anything not finite or outside [lo, hi],
// naming the accepted range. Header-only, for programs that use CLI11.

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>

namespace tsmh::files {

/// A CLI11 check: a finite number within [lo, hi] (`unit` appended, e.g. "s").
inline CLI::Validator finite_range(double lo, double hi, const std::string& unit) {
  std::ostringstream range;
  range << "[" << lo << ", " << hi << "]" << (unit.empty() ? "" : " " + unit);
  const std::string text = range.str();
  return CLI::Validator(
      [lo, hi, text](std::string& value) -> std::string {
        const char* begin = value.c_str();
        char* end = nullptr;
        const double v = std::strtod(begin, &end);
        if (end == begin || *end != '\0')
          return "not a number: '" + value + "' (expected " + text + ")";
        if (!std::isfinite(v) || v < lo || v > hi)
          return "must be a finite number within " + text + ", got " + value;
        return "";
      },
      text);
}

}  // namespace tsmh::files
