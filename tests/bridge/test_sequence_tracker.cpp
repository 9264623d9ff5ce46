#include <gtest/gtest.h>

#include "bridge/sequence_tracker.hpp"

namespace tsmh::bridge {
namespace {

TEST(SequenceTracker, ClassifiesOrderAndCountsMissing) {
  SequenceTracker t;
  EXPECT_EQ(t.observe(10, 1000).order, Order::kFirst);
  EXPECT_EQ(t.observe(11, 1001).order, Order::kNext);
  const OrderVerdict gap = t.observe(15, 1005);
  EXPECT_EQ(gap.order, Order::kGap);
  EXPECT_EQ(gap.missing, 3);
  EXPECT_EQ(t.observe(15, 1005).order, Order::kDuplicate);
  EXPECT_EQ(t.observe(13, 1003).order, Order::kLate);
  EXPECT_EQ(t.observe(16, 1005).order, Order::kTimeBackwards) << "utime must increase with seq";
  EXPECT_EQ(t.observe(16, 1004).order, Order::kTimeBackwards);
  EXPECT_EQ(t.last_seq(), 15) << "dropped messages do not move the reference";
  EXPECT_EQ(t.observe(16, 1006).order, Order::kNext);
}

TEST(SequenceTracker, SenderRestartIsAccepted) {
  SequenceTracker t;
  t.observe(500, 10'000);
  const OrderVerdict v = t.observe(0, 20'000);  // new process: seq from 0, later time
  EXPECT_EQ(v.order, Order::kRestart);
  EXPECT_TRUE(v.accepted());
  EXPECT_EQ(t.observe(1, 20'001).order, Order::kNext);
}

TEST(SequenceTracker, ResyncsAfterABogusReference) {
  // One message with a far-future utime and seq must not silence the channel forever.
  SequenceTracker t(/*resync_after=*/5);
  t.observe(1, 1000);
  EXPECT_EQ(t.observe(1'000'000, 9'000'000'000).order, Order::kGap);
  for (int i = 0; i < 4; ++i)
    EXPECT_EQ(t.observe(2 + i, 1001 + i).order, Order::kLate) << "message " << i;
  const OrderVerdict v = t.observe(6, 1005);
  EXPECT_EQ(v.order, Order::kResync);
  EXPECT_TRUE(v.accepted());
  EXPECT_EQ(t.observe(7, 1006).order, Order::kNext);
}

TEST(SequenceTracker, DuplicatesNeverForceAResync) {
  // A stuck sender repeating one message must not look fresh.
  SequenceTracker t(/*resync_after=*/3);
  t.observe(4, 100);
  for (int i = 0; i < 10; ++i)
    EXPECT_EQ(t.observe(4, 100).order, Order::kDuplicate);
}

// Garbage seq values: the distance from INT64_MIN to INT64_MAX
// does not fit an int64; `missing` saturates instead of overflowing.
TEST(SequenceTracker, ExtremeSeqJumpsSaturateInsteadOfOverflowing) {
  SequenceTracker t;
  t.observe(INT64_MIN, 1);
  const OrderVerdict v = t.observe(INT64_MAX, 2);
  EXPECT_EQ(v.order, Order::kGap);
  EXPECT_EQ(v.missing, INT64_MAX);
  EXPECT_EQ(t.observe(INT64_MIN + 1, 3).order, Order::kRestart);
  EXPECT_EQ(t.observe(INT64_MIN + 2, 4).order, Order::kNext);
}

}  // namespace
}  // namespace tsmh::bridge
