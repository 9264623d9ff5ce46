// Inbox logic fed directly with bytes (no network): what reaches the loop,
// what is counted, and how a rejection is described.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "bridge/inbox.hpp"
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
  EXPECT_EQ(st.rejected(RejectReason::kNonFinite), 1U);
  EXPECT_EQ(st.rejected(RejectReason::kJointCount), 1U);
  EXPECT_EQ(st.rejected(RejectReason::kDecode), 1U);
  EXPECT_EQ(st.rejected(RejectReason::kTimeBackwards), 1U);
  EXPECT_EQ(st.rejected(), 4U);
  EXPECT_EQ(st.duplicates, 1U);
  EXPECT_EQ(st.reordered, 1U);
  EXPECT_EQ(st.seq_gaps, 1U) << "one gap event";
  EXPECT_EQ(st.seq_missing, 4U);
  EXPECT_EQ(st.dropped(), 6U);
  EXPECT_EQ(st.received, st.accepted + st.dropped());
  EXPECT_EQ(st.last_receive_ns, 1'600'000);
  // Latency = receive - utime: 1.1 ms - 1 ms = 100 us and 1.6 ms - 1.005 ms = 595 us.
  EXPECT_EQ(st.latency.count, 2U);
  EXPECT_EQ(st.latency.min_us, 100.0);
  EXPECT_EQ(st.latency.max_us, 595.0);

  const auto last = in.last_rejection();
  ASSERT_TRUE(last.has_value());
  EXPECT_EQ(last->reason, RejectReason::kTimeBackwards);
  EXPECT_EQ(last->seq, 6);
  EXPECT_NE(describe(*last, in.channel()).find("X_SLAVE_STATE seq 6"), std::string::npos);
}

TEST(Inbox, ConfiguredRangesReject) {
  SlaveStateLimits tight;
  tight.x_in = {-0.5, 0.5};
  Inbox<SlaveStateSample> in("C", {.limits = tight, .clocks_shared = false});
  feed(in, make_state(0, 1), 10);  // x_in[1] = 1.0 is outside
  EXPECT_EQ(in.stats().rejected(RejectReason::kOutOfRange), 1U);
  auto one_joint = make_state(1, 2, 1);
  feed(in, one_joint, 20);
  EXPECT_EQ(in.stats().accepted, 1U);
  EXPECT_EQ(in.stats().latency.count, 0U) << "clocks not shared: no latency";
  const auto r = in.last_rejection();
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(describe(*r, "C"), "C seq 0: x_in[1] = 1 is outside its configured range");
}

// seq_gaps counts gap events: one jump of two trillion is one gap (not
// 2,000,000,000,001), and hostile jumps never overflow.
TEST(Inbox, SeqGapsCountEventsNotDistances) {
  Inbox<SlaveStateSample> in("X_SLAVE_STATE", {.expected_joints = 2});
  auto s = make_state(0, 1000);
  feed(in, s, 1'000'000);
  s.seq = 2'000'000'000'002;
  s.utime = 2000;
  feed(in, s, 2'000'000);
  EXPECT_EQ(in.stats().seq_gaps, 1U);
  EXPECT_EQ(in.stats().seq_missing, 2'000'000'000'001U);
  for (int i = 0; i < 6; ++i) {  // alternate extremes: each is a restart or a huge gap
    s.seq = (i % 2) ? INT64_MAX - i : INT64_MIN + i;
    s.utime = 3000 + i;
    feed(in, s, 3'000'000 + i);
  }
  const ChannelStats st = in.stats();
  EXPECT_EQ(st.seq_gaps, 4U) << "1 + one per jump up";
  EXPECT_EQ(st.seq_missing, UINT64_MAX) << "saturated";
  EXPECT_EQ(st.restarts, 3U);
}

// Plausible garbage: messages with a valid header and joint count
// but a random body -- every field inside its configured range, random seq and
// utime -- interleaved with a smooth 1 kHz stream. Before the step check 8 of
// 2000 such messages were accepted (x_in -7.6 rad from ~0), now none is, and
// the genuine stream still gets through.
TEST(Inbox, RejectsPhysicallyImpossibleStepsFromRandomBodies) {
  Inbox<SlaveStateSample> in("X_SLAVE_STATE", {.expected_joints = 2});
  std::mt19937_64 rng(15);
  auto uniform = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  const SlaveStateLimits lim;
  std::int64_t now_ns = 1'000'000'000;
  std::int64_t seq = 0;
  std::uint64_t garbage_seen = 0, genuine_sent = 0;
  for (int k = 0; k < 2000; ++k) {
    // The genuine stream: slow sines, one sample per millisecond.
    now_ns += 1'000'000;
    const double t = static_cast<double>(now_ns) * 1e-9;
    SlaveStateSample g = make_state(seq++, now_ns / 1000);
    for (std::size_t j = 0; j < 2; ++j) {
      g.x_in[j] = 2.0 * std::sin(3.0 * t + static_cast<double>(j));
      g.x_out[j] = 0.5 * std::sin(3.0 * t + static_cast<double>(j));
      g.T1[j] = 20.0 + 5.0 * std::sin(7.0 * t);
      g.T3[j] = 20.0 - 5.0 * std::sin(7.0 * t);
    }
    feed(in, g, now_ns);
    ++genuine_sent;
    // One (sometimes a burst of) random-body messages right after it.
    const int burst = k % 100 == 0 ? 60 : 1;
    for (int b = 0; b < burst; ++b) {
      SlaveStateSample r;
      r.num_joints = 2;
      r.seq = static_cast<std::int64_t>(rng() >> 1) % 4 == 0
                  ? seq + 1 + static_cast<int>(rng() % 1000)
                  : static_cast<std::int64_t>(rng());
      r.utime = now_ns / 1000 + static_cast<std::int64_t>(rng() % 2'000'000) - 1'000'000;
      r.status = 1;
      for (std::size_t j = 0; j < 2; ++j) {
        r.x_in[j] = uniform(-10.0, 10.0);
        r.x_out[j] = uniform(lim.x_out.lo, lim.x_out.hi);
        r.T1[j] = uniform(-200.0, 500.0);
        r.T3[j] = uniform(-200.0, 500.0);
        r.radius_m[j] = 0.01;
      }
      feed(in, r, now_ns + 10'000 + b);
      ++garbage_seen;
    }
    SlaveStateSample got;
    ASSERT_NE(in.latest(got), 0U);
    ASSERT_LE(std::fabs(got.x_in[0] - g.x_in[0]), 0.1)
        << "message " << k << ": a random body reached the loop (seq " << got.seq << ")";
  }
  const ChannelStats st = in.stats();
  EXPECT_GE(st.rejected(RejectReason::kImplausible), garbage_seen * 9 / 10);
  EXPECT_GE(st.accepted, genuine_sent * 9 / 10) << "the genuine stream must still get through";
  EXPECT_EQ(st.resyncs, 0U) << "bursts of garbage must never look like a re-homed slave";
}

// A slave that really jumps (re-homed) is accepted again after resync_after
// samples that follow each other plausibly.
TEST(Inbox, RebasesOnAConsistentNewTrajectory) {
  Inbox<SlaveStateSample> in("X_SLAVE_STATE", {.expected_joints = 2, .resync_after = 5});
  std::int64_t now_ns = 1'000'000'000;
  for (int k = 0; k < 3; ++k) {
    now_ns += 1'000'000;
    feed(in, make_state(k, now_ns / 1000), now_ns);
  }
  for (int k = 3; k < 10; ++k) {
    now_ns += 1'000'000;
    auto s = make_state(k, now_ns / 1000);
    s.x_in[0] += 50.0;  // 50 rad away in one period
    feed(in, s, now_ns);
  }
  const ChannelStats st = in.stats();
  EXPECT_EQ(st.rejected(RejectReason::kImplausible), 4U);
  EXPECT_EQ(st.resyncs, 1U);
  SlaveStateSample got;
  ASSERT_EQ(in.latest(got), 3U + 3U) << "3 before, then the 5th of the new trajectory on";
  EXPECT_EQ(got.seq, 9);
  const auto r = in.last_rejection();
  ASSERT_TRUE(r.has_value());
  EXPECT_NE(describe(*r, in.channel()).find("x_in[0] stepped by 50"), std::string::npos)
      << describe(*r, in.channel());
}

}  // namespace
}  // namespace tsmh::bridge
