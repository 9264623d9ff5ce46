// The estimator's one quantile rule (rank floor(q (n-1)), the lower sample)
// and call sites that read thresholds off data through it.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "estimator/fit_metrics.hpp"
#include "estimator/quantile.hpp"
#include "estimator/recording_checks.hpp"

namespace tsmh::estimator {
namespace {

TEST(Quantile, RankIsFloorOfQTimesNMinusOne) {
  const std::vector<double> v = {5.0, 1.0, 4.0, 2.0, 3.0};
  EXPECT_EQ(quantile(v, 0.0), 1.0);
  EXPECT_EQ(quantile(v, 0.5), 3.0);
  EXPECT_EQ(quantile(v, 0.95), 4.0);  // rank floor(3.8) = 3, not the maximum
  EXPECT_EQ(quantile(v, 1.0), 5.0);
  EXPECT_EQ(quantile(v, 2.0), 5.0);  // clamped, never past the end
  EXPECT_EQ(quantile(v, -1.0), 1.0);
}

TEST(Quantile, MedianOfAnEvenCountIsTheLowerMiddleSample) {
  EXPECT_EQ(median({4.0, 1.0, 3.0, 2.0}), 2.0);
  EXPECT_EQ(median({7.0}), 7.0);
}

TEST(Quantile, EmptySetOrNanQGivesNan) {
  EXPECT_TRUE(std::isnan(quantile({}, 0.5)));
  EXPECT_TRUE(std::isnan(median({})));
  EXPECT_TRUE(std::isnan(quantile({1.0, 2.0}, std::nan(""))));
}

// noise_floor = median |second difference| / (0.6745 sqrt 6). Second
// differences of magnitude 1, 2, 3, 4: the median is 2 by the rule (the
// helper it used to carry took the upper middle sample, 3).
TEST(Quantile, NoiseFloorUsesTheLowerMedian) {
  const std::vector<double> y = {0.0, 0.0, 1.0, 4.0, 10.0, 20.0};
  EXPECT_DOUBLE_EQ(noise_floor(y), 2.0 / (0.6745 * std::sqrt(6.0)));
}

// The time-unit check warns when the median step is >= 0.5 (milliseconds
// mistaken for seconds). 100 steps, half 0.4 and half 0.6: the median is
// 0.4 by the rule, so no warning; with a median of 0.6 it would warn.
TEST(Quantile, TimeUnitCheckUsesTheSameMedian) {
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
