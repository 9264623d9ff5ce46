// Inbox logic fed directly with bytes (no network): what reaches the loop,
// what is counted, and how a rejection is described.
#include "bridge/inbox.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "test_support.hpp"

namespace tsmh::bridge {
namespace {

using test::make_state;

std::vector<std::uint8_t> bytes_of(const SlaveStateSample& s) {
  std::vector<std::uint8_t> b;
  encode_sample(s, b);
  return b;
}

void feed(Inbox<SlaveStateSample>& in, const SlaveStateSample& s, std::int64_t receive_ns) {
  const auto b = bytes_of(s);
  in.ingest(b.data(), b.size(), receive_ns);
}

TEST(Inbox, KeepsNewestValidSampleAndCountsEverything) {
  Inbox<SlaveStateSample> in("X_SLAVE_STATE", {.expected_joints = 2});
  SlaveStateSample got;
  EXPECT_EQ(in.latest(got), 0U);

  feed(in, make_state(0, 1000), 1'100'000);
  ASSERT_EQ(in.latest(got), 1U);
  EXPECT_EQ(got.seq, 0);
  EXPECT_EQ(got.receive_ns, 1'100'000);
  EXPECT_EQ(receive_age_ns(got, 1'600'000), 500'000);

  auto nan = make_state(1, 1001);
  nan.T1[0] = std::nan("");
  feed(in, nan, 1'200'000);
  feed(in, make_state(2, 1002, 3), 1'300'000);  // 3 joints, configured for 2
  feed(in, make_state(0, 1000), 1'400'000);     // duplicate
  const std::uint8_t garbage[5] = {1, 2, 3, 4, 5};
  in.ingest(garbage, sizeof garbage, 1'500'000);
  feed(in, make_state(5, 1005), 1'600'000);  // gap: 1..4 never accepted
  feed(in, make_state(4, 1004), 1'700'000);  // late
  feed(in, make_state(6, 1003), 1'800'000);  // seq up, time down

  ASSERT_EQ(in.latest(got), 2U) << "only seq 0 and seq 5 were accepted";
  EXPECT_EQ(got.seq, 5);
  EXPECT_EQ(got.x_in[1], 0.005 + 1);

  const ChannelStats st = in.stats();
  EXPECT_EQ(st.received, 8U);
  EXPECT_EQ(st.accepted, 2U);
  EXPECT_EQ(st.rejected(RejectReason::NonFinite), 1U);
  EXPECT_EQ(st.rejected(RejectReason::JointCount), 1U);
  EXPECT_EQ(st.rejected(RejectReason::Decode), 1U);
  EXPECT_EQ(st.rejected(RejectReason::TimeBackwards), 1U);
  EXPECT_EQ(st.rejected(), 4U);
  EXPECT_EQ(st.duplicates, 1U);
  EXPECT_EQ(st.reordered, 1U);
  EXPECT_EQ(st.seq_gaps, 4U);
  EXPECT_EQ(st.dropped(), 6U);
  EXPECT_EQ(st.received, st.accepted + st.dropped());
  EXPECT_EQ(st.last_receive_ns, 1'600'000);
  // Latency = receive - utime: 1.1 ms - 1 ms = 100 us and 1.6 ms - 1.005 ms = 595 us.
  EXPECT_EQ(st.latency.count, 2U);
  EXPECT_EQ(st.latency.min_us, 100.0);
  EXPECT_EQ(st.latency.max_us, 595.0);

  const auto last = in.last_rejection();
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->reason, RejectReason::TimeBackwards);
  EXPECT_EQ(last->seq, 6);
  EXPECT_NE(describe(*last, in.channel()).find("X_SLAVE_STATE seq 6"), std::string::npos);
}

TEST(Inbox, ConfiguredRangesReject) {
  SlaveStateLimits tight;
  tight.x_in = {-0.5, 0.5};
  Inbox<SlaveStateSample> in("C", {.limits = tight, .clocks_shared = false});
  feed(in, make_state(0, 1), 10);  // x_in[1] = 1.0 is outside
  EXPECT_EQ(in.stats().rejected(RejectReason::OutOfRange), 1U);
  auto one_joint = make_state(1, 2, 1);
  feed(in, one_joint, 20);
  EXPECT_EQ(in.stats().accepted, 1U);
  EXPECT_EQ(in.stats().latency.count, 0U) << "clocks not shared: no latency";
  const auto r = in.last_rejection();
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(describe(*r, "C"), "C seq 0: x_in[1] = 1 is outside its configured range");
}

}  // namespace
}  // namespace tsmh::bridge
