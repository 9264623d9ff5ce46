// Estimator call sites that read thresholds off data through the one
// quantile rule (realtime/quantile.hpp: rank floor(q (n-1)), the lower sample).
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "estimator/fit_metrics.hpp"
#include "estimator/recording_checks.hpp"

namespace tsmh::estimator {
namespace {

// noise_floor = median |second difference| / (0.6745 sqrt 6). Second
// differences of magnitude 1, 2, 3, 4: the median is 2 by the rule (the
// helper it used to carry took the upper middle sample, 3).
TEST(QuantileUse, NoiseFloorUsesTheLowerMedian) {
  const std::vector<double> y = {0.0, 0.0, 1.0, 4.0, 10.0, 20.0};
  EXPECT_DOUBLE_EQ(noise_floor(y), 2.0 / (0.6745 * std::sqrt(6.0)));
}

// The time-unit check warns when the median step is >= 0.5 (milliseconds
// mistaken for seconds). 100 steps, half 0.4 and half 0.6: the median is
// 0.4 by the rule, so no warning; with a median of 0.6 it would warn.
TEST(QuantileUse, TimeUnitCheckUsesTheSameMedian) {
  std::vector<double> t = {0.0};
  for (int i = 0; i < 100; ++i)
    t.push_back(t.back() + (i % 2 == 0 ? 0.4 : 0.6));
  EXPECT_EQ(time_unit_warning(t), "");
  for (double& s : t)
    s *= 1.5;  // steps 0.6 and 0.9: the median 0.6 is >= 0.5
  EXPECT_NE(time_unit_warning(t), "");
}

}  // namespace
}  // namespace tsmh::estimator
