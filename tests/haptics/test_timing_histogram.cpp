// Percentiles of the loop's timing histogram.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "haptics/timing_histogram.hpp"

namespace tsmh::haptics {
namespace {

TEST(TimingHistogram, Percentiles) {
  TimingHistogram h;
  for (int i = 1; i <= 1000; ++i)
    h.record(i * 1000);  // 1..1000 us
  const auto s = h.summary();
  EXPECT_EQ(s.count, 1000u);
  EXPECT_NEAR(s.p50_us, 500, 1.0);
  EXPECT_NEAR(s.p99_us, 990, 1.0);
  EXPECT_NEAR(s.max_us, 1000, 1e-9);
  EXPECT_NEAR(s.mean_us, 500.5, 1e-9);
  h.record(50'000'000);  // beyond the linear range: still the exact max
  EXPECT_NEAR(h.summary().max_us, 50000, 1e-9);
}

}  // namespace
}  // namespace tsmh::haptics
