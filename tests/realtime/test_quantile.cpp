// The project's one quantile rule (rank floor(q (n-1)), always a sample) and
// the benchmarks' percentile summary built on it.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "realtime/quantile.hpp"

namespace tsmh::realtime {
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

// The benchmarks' summary reads the same ranks as quantile(). The helpers it
// replaced disagreed: one took rank floor(q n) (p50 of 1..4 was 3), one the
// nearest rank ceil(q n) (p99 of 1..10 was 10, the maximum).
TEST(Quantile, PercentilesUseTheSameRule) {
  const Percentiles four = percentiles({4.0, 2.0, 1.0, 3.0});
  EXPECT_EQ(four.p50, 2.0);
  EXPECT_EQ(four.max, 4.0);
  EXPECT_DOUBLE_EQ(four.mean, 2.5);
  EXPECT_EQ(four.count, 4u);
  std::vector<double> ten;
  for (int i = 10; i >= 1; --i)
    ten.push_back(i);
  const Percentiles p = percentiles(ten);
  EXPECT_EQ(p.p99, 9.0);
  EXPECT_EQ(p.p99, quantile(ten, 0.99));
  EXPECT_EQ(p.p90, quantile(ten, 0.9));
  EXPECT_EQ(p.p999, quantile(ten, 0.999));
  const Percentiles none = percentiles({});
  EXPECT_EQ(none.count, 0u);
  EXPECT_TRUE(std::isnan(none.p50));
}

}  // namespace
}  // namespace tsmh::realtime
