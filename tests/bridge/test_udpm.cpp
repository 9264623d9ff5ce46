// Receiver and Sender over real UDP multicast on this host (ttl=0), between
// threads and between processes.
#include <gtest/gtest.h>

#include <cmath>
#include <lcm/lcm-cpp.hpp>
#include <random>
#include <thread>

#include "bridge/receiver.hpp"
#include "bridge/sender.hpp"
#include "process.hpp"
#include "realtime/clock.hpp"
#include "test_support.hpp"

namespace tsmh::bridge {
namespace {

using namespace std::chrono_literals;
using test::make_state;
using test::wait_until;

TEST(Udpm, LoopSeesNewestSampleAndItsAge) {
  const BridgeConfig cfg{.url = test::test_url(), .prefix = test::unique_prefix()};
  Receiver rx(cfg);
  auto& slave = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  rx.start();
  Sender tx(cfg);
  auto& out = tx.outbox<SlaveStateSample>();
  tx.start();

  constexpr int kCount = 300;
  std::thread slave_node([&] {  // a 1 kHz sender, absolute deadlines
    std::int64_t next = realtime::monotonic_now_ns();
    for (int i = 0; i < kCount; ++i) {
      // A test sender may wait for ring space (a real-time loop would drop and
      // count): every message must go out even when this machine stalls.
      while (!out.publish(make_state(i, realtime::monotonic_utime())))
        std::this_thread::sleep_for(1ms);
      next += 1'000'000;
      realtime::sleep_until_ns(next);
    }
  });

  // The "loop": read every 250 us while the sender runs.
  std::uint64_t last_version = 0, reads_with_value = 0, version_went_back = 0, seq_went_back = 0;
  std::int64_t last_seq = -1, max_age_ns = 0;
  SlaveStateSample s;
  const auto until = std::chrono::steady_clock::now() + 10s;
  while (last_seq < kCount - 1 && std::chrono::steady_clock::now() < until) {
    const std::uint64_t v = slave.latest(s);
    if (v != 0) {
      ++reads_with_value;
      if (v < last_version) ++version_went_back;
      if (s.seq < last_seq) ++seq_went_back;
      EXPECT_EQ(s.x_in[1], 0.001 * static_cast<double>(s.seq) + 1) << "payload matches its seq";
      max_age_ns = std::max(max_age_ns, receive_age_ns(s, realtime::monotonic_now_ns()));
      last_version = v;
      last_seq = s.seq;
    }
    std::this_thread::sleep_for(250us);
  }
  slave_node.join();

  EXPECT_GT(reads_with_value, 0U);
  EXPECT_EQ(version_went_back, 0U);
  EXPECT_EQ(seq_went_back, 0U);
  EXPECT_EQ(last_seq, kCount - 1) << "the loop ends up with the newest sample";
  EXPECT_GE(max_age_ns, 0);

  // Nothing new arrives: the age keeps growing, which is how the loop detects a dead slave.
  ASSERT_TRUE(slave.latest(s));
  std::this_thread::sleep_for(30ms);
  EXPECT_GE(receive_age_ns(s, realtime::monotonic_now_ns()), 30'000'000);
  EXPECT_GE(sample_age_ns(s, realtime::monotonic_now_ns()), 30'000'000)
      << "same host: utime shares the clock";

  ASSERT_TRUE(wait_until([&] { return slave.stats().accepted == kCount; }))
      << "accepted " << slave.stats().accepted;
  const ChannelStats st = slave.stats();
  EXPECT_EQ(st.received, static_cast<std::uint64_t>(kCount));
  EXPECT_EQ(st.dropped(), 0U);
  EXPECT_EQ(st.seq_gaps, 0U);
  EXPECT_EQ(st.latency.count, static_cast<std::uint64_t>(kCount));
  EXPECT_GE(st.latency.min_us, 0.0);
  EXPECT_EQ(out.stats().published, static_cast<std::uint64_t>(kCount));
}

TEST(Udpm, HostileMessagesAreCountedAndNeverReachTheLoop) {
  const std::string prefix = test::unique_prefix();
  Receiver rx({.url = test::test_url(), .prefix = prefix});
  auto& slave = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  rx.start();
  auto raw = open_lcm(test::test_url());
  const std::string ch = channel_name(prefix, Channel::kSlaveState);
  int sent = 0;
  auto send_bytes = [&](const std::vector<std::uint8_t>& b) {
    ASSERT_EQ(raw->publish(ch, b.data(), static_cast<unsigned>(b.size())), 0);
    ++sent;
  };
  auto send = [&](const SlaveStateSample& s) {
    std::vector<std::uint8_t> b;
    encode_sample(s, b);
    send_bytes(b);
  };
  const std::int64_t t0 = realtime::monotonic_utime();

  send(make_state(0, t0));  // valid
  auto nan = make_state(1, t0 + 1);
  nan.x_in[0] = std::nan("");
  send(nan);
  auto inf = make_state(2, t0 + 2);
  inf.T1[1] = -INFINITY;
  send(inf);
  auto range = make_state(3, t0 + 3);
  range.radius_m[0] = 5.0;
  send(range);
  send(make_state(4, t0 + 4, 3));  // wrong joint count
  std::vector<std::uint8_t> good;
  encode_sample(make_state(5, t0 + 5), good);
  auto huge = good;
  huge[24] = 0x7f;  // num_joints = 0x7f000002
  send_bytes(huge);
  auto negative = good;
  negative[24] = 0xff;  // num_joints < 0
  send_bytes(negative);
  send_bytes({good.begin(), good.begin() + 40});  // truncated
  std::mt19937 rng(3);
  std::vector<std::uint8_t> garbage(200);
  for (auto& b : garbage)
    b = static_cast<std::uint8_t>(rng());
  send_bytes(garbage);
  MasterCommandSample wrong_type;
  wrong_type.num_joints = 2;
  std::vector<std::uint8_t> other;
  encode_sample(wrong_type, other);
  send_bytes(other);              // a master_command_t on the SLAVE_STATE channel
  send(make_state(0, t0));        // duplicate of the first
  send(make_state(5, t0 - 100));  // seq advances, time goes back
  send(make_state(6, t0 + 6));    // valid

  ASSERT_TRUE(wait_until([&] {
    return slave.stats().received == static_cast<std::uint64_t>(sent);
  })) << "received "
      << slave.stats().received << " of " << sent;
  const ChannelStats st = slave.stats();
  EXPECT_EQ(st.accepted, 2U);
  EXPECT_EQ(st.rejected(RejectReason::kNonFinite), 2U);
  EXPECT_EQ(st.rejected(RejectReason::kOutOfRange), 1U);
  EXPECT_EQ(st.rejected(RejectReason::kJointCount), 3U);
  EXPECT_EQ(st.rejected(RejectReason::kDecode), 3U);
  EXPECT_EQ(st.rejected(RejectReason::kTimeBackwards), 1U);
  EXPECT_EQ(st.duplicates, 1U);
  EXPECT_EQ(st.seq_gaps, 1U) << "one gap: seq 1..5 never accepted";
  EXPECT_EQ(st.seq_missing, 5U);
  EXPECT_EQ(st.received, st.accepted + st.dropped());

  SlaveStateSample s;
  EXPECT_EQ(slave.latest(s), 2U) << "only the two valid samples were ever stored";
  EXPECT_EQ(s.seq, 6);
  for (int j = 0; j < 2; ++j) {
    EXPECT_TRUE(std::isfinite(s.x_in[static_cast<std::size_t>(j)]));
    EXPECT_TRUE(std::isfinite(s.T1[static_cast<std::size_t>(j)]));
  }
  EXPECT_EQ(rx.transport_errors(), 0U);
}

TEST(Udpm, TwoProcessesSlaveStateAndTruth) {
  const std::string prefix = test::unique_prefix();
  Receiver rx({.url = test::test_url(), .prefix = prefix});
  auto& state = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  auto& truth = rx.subscribe<SlaveTruthSample>({.expected_joints = 2});
  rx.start();

  const auto peer =
      test::run({TSMH_BRIDGE_PEER, "publish", test::test_url(), prefix, "400", "1000", "truth"});
  ASSERT_EQ(peer.exit_code, 0) << peer.output;
  ASSERT_TRUE(wait_until([&] {
    return state.stats().accepted == 400 && truth.stats().accepted == 400;
  })) << "state "
      << state.stats().accepted << " truth " << truth.stats().accepted;

  SlaveStateSample s;
  SlaveTruthSample t;
  ASSERT_EQ(state.latest(s), 400U);
  ASSERT_EQ(truth.latest(t), 400U);
  EXPECT_EQ(s.seq, 399);
  EXPECT_EQ(t.seq, 399);
  EXPECT_EQ(t.tau_out[0], test::make_truth(399, 0).tau_out[0]);
  const ChannelStats st = state.stats();
  EXPECT_EQ(st.seq_gaps, 0U);
  EXPECT_EQ(st.dropped(), 0U);
  EXPECT_EQ(st.latency.count, 400U);
  EXPECT_GE(st.latency.min_us, 0.0) << "same host, same CLOCK_MONOTONIC";
  EXPECT_LE(st.latency.p50_us, st.latency.p99_us);
}

TEST(Udpm, MasterSideAndSlaveSideExchangeCommandsAndState) {
  // Both directions at once: the haptic server side publishes MASTER_COMMAND
  // and HAPTIC_STATUS, the slave side answers with SLAVE_STATE.
  const BridgeConfig cfg{.url = test::test_url(), .prefix = test::unique_prefix()};
  Receiver slave_rx(cfg);
  auto& cmd_in = slave_rx.subscribe<MasterCommandSample>({.expected_joints = 2});
  slave_rx.start();
  Sender slave_tx(cfg);
  auto& state_out = slave_tx.outbox<SlaveStateSample>();
  slave_tx.start();
  Receiver master_rx(cfg);
  auto& state_in = master_rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  auto& status_in = master_rx.subscribe<HapticStatusSample>();
  master_rx.start();
  Sender master_tx(cfg);
  auto& cmd_out = master_tx.outbox<MasterCommandSample>();
  auto& status_out = master_tx.outbox<HapticStatusSample>();
  master_tx.start();

  for (int i = 0; i < 50; ++i) {
    MasterCommandSample c;
    c.utime = realtime::monotonic_utime();
    c.seq = i;
    c.num_joints = 2;
    c.position_ref = {0.01 * i, -0.01 * i};
    c.enable = true;
    ASSERT_TRUE(cmd_out.publish(c));
    std::this_thread::sleep_for(1ms);
    MasterCommandSample got;
    if (cmd_in.latest(got)) {  // the slave follows the newest command
      SlaveStateSample s = make_state(i, realtime::monotonic_utime());
      s.x_out[0] = got.position_ref[0];               // what the slave follows
      s.status = static_cast<std::int32_t>(got.seq);  // and which command that was
      state_out.publish(s);
    }
    if (i % 10 == 0) {
      HapticStatusSample h;
      h.utime = realtime::monotonic_utime();
      h.seq = i / 10;
      h.num_joints = 2;
      h.rate_hz = 1000.0;
      h.tau_out_est = {std::nan(""), 0.1};  // NaN is allowed in status
      status_out.publish(h);
    }
  }
  ASSERT_TRUE(wait_until([&] { return cmd_in.stats().accepted == 50; }));
  ASSERT_TRUE(wait_until([&] { return status_in.stats().accepted == 5; }));
  ASSERT_TRUE(wait_until([&] { return state_in.stats().accepted > 0; }));
  SlaveStateSample s;
  ASSERT_NE(state_in.latest(s), 0U);
  // The state carries a command that was really sent (its payload matches its
  // seq), and never one newer than the tick that produced the state.
  EXPECT_EQ(s.x_out[0], 0.01 * s.status) << "payload of command seq " << s.status;
  EXPECT_LE(s.status, s.seq);
  HapticStatusSample h;
  ASSERT_EQ(status_in.latest(h), 5U);
  EXPECT_EQ(h.seq, 4);
  EXPECT_TRUE(std::isnan(h.tau_out_est[0]));
}

TEST(Udpm, PrefixesSeparateArms) {
  const std::string base = test::unique_prefix();
  Receiver rx1({.url = test::test_url(), .prefix = base + "ARM1_"});
  auto& arm1 = rx1.subscribe<SlaveStateSample>();
  rx1.start();
  Receiver rx2({.url = test::test_url(), .prefix = base + "ARM2_"});
  auto& arm2 = rx2.subscribe<SlaveStateSample>();
  rx2.start();
  Sender tx({.url = test::test_url(), .prefix = base + "ARM2_"});
  auto& out = tx.outbox<SlaveStateSample>();
  tx.start();
  out.publish(make_state(7, realtime::monotonic_utime()));
  ASSERT_TRUE(wait_until([&] { return arm2.stats().accepted == 1; }));
  std::this_thread::sleep_for(20ms);
  EXPECT_EQ(arm1.stats().received, 0U);
}

}  // namespace
}  // namespace tsmh::bridge
