// The timing histograms: log-linear buckets (per-channel latency, the loop's
// one-second windows) and 1 us linear ones (the loop's run report).
#include <gtest/gtest.h>

#include "realtime/histogram.hpp"

namespace tsmh::realtime {
namespace {

TEST(LogHistogram, BucketsAreContiguousAndWithinAnEighth) {
  for (std::uint64_t us = 0; us < 100'000; ++us) {
    const int b = LogHistogram::bucket_of(us);
    ASSERT_LT(us, LogHistogram::bucket_upper(b)) << us;
    if (b > 0) {
      ASSERT_GE(us, LogHistogram::bucket_upper(b - 1)) << us;
    }
    if (us >= 16) {
      ASSERT_LE(LogHistogram::bucket_upper(b), us + us / 8 + 1) << us;
    }
  }
  EXPECT_LT(LogHistogram::bucket_of(~0ULL), LogHistogram::kBuckets);
}

TEST(LogHistogram, SummaryOfKnownSamples) {
  LogHistogram h;
  EXPECT_EQ(h.summary().count, 0U);
  // 98 samples of 10 us, one of 100 us, one of 1000 us.
  for (int i = 0; i < 98; ++i)
    h.record(10'000);
  h.record(100'000);
  h.record(1'000'000);
  h.record(-5);  // clock skew: recorded as 0
  const HistogramSummary s = h.summary();
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
  const HistogramSummary w = h.summary();
  EXPECT_EQ(w.count, 1U);
  EXPECT_EQ(w.min_us, 3.0);
  EXPECT_EQ(w.max_us, 3.0);
  EXPECT_EQ(w.p99_us, 3.0) << "capped at the exact maximum";
}

TEST(LinearHistogram, PercentilesToTheMicrosecond) {
  LinearHistogram h;
  for (int i = 1; i <= 1000; ++i)
    h.record(i * 1000);  // 1..1000 us
  const auto s = h.summary();
  EXPECT_EQ(s.count, 1000u);
  EXPECT_NEAR(s.p50_us, 500, 1.0);
  EXPECT_NEAR(s.p99_us, 990, 1.0);
  EXPECT_NEAR(s.p999_us, 999, 1.0);
  EXPECT_NEAR(s.min_us, 1, 1e-9);
  EXPECT_NEAR(s.max_us, 1000, 1e-9);
  EXPECT_NEAR(s.mean_us, 500.5, 1e-9);
  h.record(50'000'000);  // beyond the linear range: counted, and still the exact max
  EXPECT_NEAR(h.summary().max_us, 50000, 1e-9);
  EXPECT_EQ(h.summary().count, 1001u);
  EXPECT_EQ(LinearHistogram::bucket_of(19'999), 19'999);
  EXPECT_EQ(LinearHistogram::bucket_of(20'000), LinearHistogram::kBuckets - 1);
  h.reset();
  EXPECT_EQ(h.summary().count, 0u);
}

}  // namespace
}  // namespace tsmh::realtime
