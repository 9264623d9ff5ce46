#include <gtest/gtest.h>

#include "bridge/latency_histogram.hpp"

namespace tsmh::bridge {
namespace {

TEST(LatencyHistogram, BucketsAreContiguousAndWithinAnEighth) {
  for (std::uint64_t us = 0; us < 100'000; ++us) {
    const int b = LatencyHistogram::bucket_of(us);
    ASSERT_LT(us, LatencyHistogram::bucket_upper(b)) << us;
    if (b > 0) {
      ASSERT_GE(us, LatencyHistogram::bucket_upper(b - 1)) << us;
    }
    if (us >= 16) {
      ASSERT_LE(LatencyHistogram::bucket_upper(b), us + us / 8 + 1) << us;
    }
  }
  EXPECT_LT(LatencyHistogram::bucket_of(~0ULL), LatencyHistogram::kBuckets);
}

TEST(LatencyHistogram, SummaryOfKnownSamples) {
  LatencyHistogram h;
  EXPECT_EQ(h.summary().count, 0U);
  // 98 samples of 10 us, one of 100 us, one of 1000 us.
  for (int i = 0; i < 98; ++i)
    h.record(10'000);
  h.record(100'000);
  h.record(1'000'000);
  h.record(-5);  // clock skew: recorded as 0
  const LatencySummary s = h.summary();
  EXPECT_EQ(s.count, 101U);
  EXPECT_EQ(s.min_us, 0.0);
  EXPECT_EQ(s.max_us, 1000.0);
  EXPECT_NEAR(s.mean_us, (98 * 10.0 + 100.0 + 1000.0) / 101.0, 1e-9);
  EXPECT_EQ(s.p50_us, 11.0) << "upper edge of the 10 us bucket";
  EXPECT_GE(s.p99_us, 100.0);
  EXPECT_LE(s.p99_us, 112.5);

  h.reset();  // a new window
  EXPECT_EQ(h.summary().count, 0U);
  h.record(3'000);
  const LatencySummary w = h.summary();
  EXPECT_EQ(w.count, 1U);
  EXPECT_EQ(w.min_us, 3.0);
  EXPECT_EQ(w.max_us, 3.0);
  EXPECT_EQ(w.p99_us, 3.0) << "capped at the exact maximum";
}

}  // namespace
}  // namespace tsmh::bridge
