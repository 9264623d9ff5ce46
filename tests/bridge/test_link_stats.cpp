// The slave-link statistics are the truth: known latency, gaps,
// reordering and duplicates injected over real udpm on this host (ttl=0, its
// own port 7731) come out as exactly those figures; messages that queued up
// before the receive thread started are discarded and counted, never read as
// huge latencies and a gap.
#include <gtest/gtest.h>

#include <lcm/lcm-cpp.hpp>
#include <thread>
#include <vector>

#include "bridge/codec.hpp"
#include "bridge/receiver.hpp"
#include "realtime/clock.hpp"
#include "test_support.hpp"

namespace tsmh::bridge {
namespace {

using namespace std::chrono_literals;
using test::make_state;
using test::wait_until;

std::string stats_url() {
  return "udpm://239.255.76.67:7731?ttl=0&recv_buf_size=2097152";
}

struct Send {
  std::int64_t seq;
  std::int64_t utime;
};

void send_paced(lcm::LCM& lcm, const std::string& channel, const std::vector<Send>& sends) {
  for (const Send& s : sends) {
    publish_sample(lcm, channel, make_state(s.seq, s.utime));
    std::this_thread::sleep_for(1ms);
  }
}

TEST(LinkStats, InjectedLatencyGapsReorderingAndDuplicatesAreCountedExactly) {
  const BridgeConfig cfg{.url = stats_url(), .prefix = test::unique_prefix()};
  Receiver rx(cfg);
  auto& inbox = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  rx.start();
  lcm::LCM lcm(stats_url());
  ASSERT_TRUE(lcm.good());

  // Every message is stamped 5 ms before it is sent: a known one-way latency.
  constexpr std::int64_t kLatencyUs = 5000;
  std::vector<std::int64_t> order;
  for (std::int64_t seq = 0; seq < 600; ++seq) {
    if (seq == 100) continue;                // gap 1: 1 missing
    if (seq >= 200 && seq <= 202) continue;  // gap 2: 3 missing
    if (seq >= 300 && seq <= 304) continue;  // gap 3: 5 missing
    if (seq == 400) continue;                // sent after 401 (below)
    order.push_back(seq);
    if (seq == 401) order.push_back(400);  // reordered: a gap of 1, then a late one
    if (seq == 500) order.push_back(500);  // a duplicate
  }
  std::vector<Send> sends;
  for (const std::int64_t seq : order)
    sends.push_back({seq, 0});
  // Paced at 1 per ms; each utime is rewritten at send time to now - 5 ms,
  // keeping 400 older than 401.
  for (std::size_t k = 0; k < sends.size(); ++k) {
    std::int64_t u = realtime::monotonic_utime() - kLatencyUs;
    if (sends[k].seq == 400) u = sends[k - 1].utime - 10;  // older than 401, sent after it
    sends[k].utime = u;
    publish_sample(lcm, inbox.channel(), make_state(sends[k].seq, u));
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_TRUE(wait_until([&] { return inbox.stats().received >= sends.size(); }, 10s))
      << "received " << inbox.stats().received << " of " << sends.size();
  std::this_thread::sleep_for(50ms);
  const ChannelStats st = inbox.stats();
  EXPECT_EQ(st.received, sends.size());
  EXPECT_EQ(st.rejected(), 0U);
  EXPECT_EQ(st.seq_gaps, 4U) << "three gaps plus the one the reordering opens";
  EXPECT_EQ(st.seq_missing, 1U + 3U + 5U + 1U);
  EXPECT_EQ(st.reordered, 1U);
  EXPECT_EQ(st.duplicates, 1U);
  EXPECT_EQ(st.accepted, sends.size() - 2);
  EXPECT_EQ(st.discarded_before_start, 0U);
  // Latency: at least the injected 5 ms; the median within the histogram's
  // 12.5 % plus a millisecond of scheduling on a busy machine.
  EXPECT_EQ(st.latency.count, st.accepted);
  EXPECT_GE(st.latency.min_us, static_cast<double>(kLatencyUs));
  EXPECT_GE(st.latency.p50_us, static_cast<double>(kLatencyUs));
  EXPECT_LE(st.latency.p50_us, kLatencyUs * 1.125 + 1000.0);
}

// A backlog handed to the loop when the receive thread starts is as old as
// the server's start-up: it would make latency p99 read that start-up and,
// past LCM's 256-message queue, sequence numbers "missing".
TEST(LinkStats, BacklogQueuedBeforeStartIsDiscardedAndCounted) {
  const BridgeConfig cfg{.url = stats_url(), .prefix = test::unique_prefix()};
  Receiver rx(cfg);
  auto& inbox = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  lcm::LCM lcm(stats_url());
  ASSERT_TRUE(lcm.good());
  std::vector<Send> before, after;
  for (std::int64_t seq = 0; seq < 40; ++seq)
    before.push_back({seq, 0});
  for (auto& s : before)
    s.utime = realtime::monotonic_utime() + s.seq;
  send_paced(lcm, inbox.channel(), before);
  std::this_thread::sleep_for(300ms);  // the "start-up"
  rx.start();
  for (std::int64_t seq = 1000; seq < 1040; ++seq) {
    publish_sample(lcm, inbox.channel(), make_state(seq, realtime::monotonic_utime()));
    std::this_thread::sleep_for(1ms);
  }
  ASSERT_TRUE(wait_until([&] { return inbox.stats().accepted >= 40; }, 10s))
      << "accepted " << inbox.stats().accepted;
  std::this_thread::sleep_for(50ms);
  const ChannelStats st = inbox.stats();
  EXPECT_EQ(st.received, 40U) << "only messages sent after start() are received";
  EXPECT_EQ(st.accepted, 40U);
  EXPECT_EQ(st.discarded_before_start, 40U);
  EXPECT_EQ(st.seq_gaps, 0U) << "the backlog is not a gap in the link";
  EXPECT_LT(st.latency.max_us, 100'000.0) << "no message 300 ms old reached the loop";
  SlaveStateSample s;
  ASSERT_NE(inbox.latest(s), 0U);
  EXPECT_EQ(s.seq, 1039);
}

}  // namespace
}  // namespace tsmh::bridge
