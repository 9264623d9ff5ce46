// The delay/loss model: the pure LinkImpairment and DelayLine, and
// the lcm-delay-relay program forwarding real LCM traffic between two udpm
// networks on this host.
#include <gtest/gtest.h>
#include <poll.h>
#include <spawn.h>
#include <sys/wait.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <vector>

#include "delay_relay/link_impairment.hpp"
#include "realtime/clock.hpp"

extern char** environ;

namespace tsmh::delay_relay {
namespace {

constexpr std::int64_t kMs = 1'000'000;

TEST(LinkImpairment, DelayStaysWithinDelayPlusMinusJitterAndOrderIsKept) {
  LinkImpairment link({.delay_s = 0.050, .jitter_s = 0.010, .drop_fraction = 0.0}, 7);
  std::int64_t prev = 0;
  double min_d = 1e9, max_d = 0, sum = 0;
  constexpr int kN = 20000;
  for (int i = 0; i < kN; ++i) {
    const std::int64_t t = i * kMs;  // 1 kHz
    const std::int64_t at = link.schedule(t);
    ASSERT_NE(at, LinkImpairment::kDropped);
    ASSERT_GE(at, prev) << "a message never overtakes an earlier one";
    prev = at;
    const double d = static_cast<double>(at - t) * 1e-6;
    min_d = std::min(min_d, d);
    max_d = std::max(max_d, d);
    sum += d;
  }
  // Order keeping can only lengthen a delay, never beyond the largest draw.
  EXPECT_GE(min_d, 40.0 - 1e-6);
  EXPECT_LE(max_d, 60.0 + 1e-6);
  EXPECT_LT(min_d, 42.0) << "jitter spreads the delays";
  EXPECT_GT(max_d, 58.0);
  // Keeping order lengthens a delay to the previous release when the draw
  // falls below it, so the mean lies between the constant and its maximum.
  EXPECT_GT(sum / kN, 50.0);
  EXPECT_LT(sum / kN, 60.0);
}

TEST(LinkImpairment, DropsTheConfiguredFraction) {
  LinkImpairment link({.delay_s = 0.01, .jitter_s = 0.0, .drop_fraction = 0.01}, 11);
  constexpr int kN = 100000;
  for (int i = 0; i < kN; ++i)
    link.schedule(i * kMs);
  // Binomial(100000, 0.01): mean 1000, sd 31.5; +-5 sd.
  EXPECT_NEAR(static_cast<double>(link.dropped()), 1000.0, 160.0);
  EXPECT_EQ(link.passed() + link.dropped(), static_cast<std::uint64_t>(kN));
}

TEST(LinkImpairment, SameSeedSameRunOtherSeedOtherRun) {
  const ImpairmentParams p{.delay_s = 0.02, .jitter_s = 0.004, .drop_fraction = 0.2};
  LinkImpairment a(p, 5), b(p, 5), c(p, 6);
  int differ = 0;
  for (int i = 0; i < 1000; ++i) {
    const std::int64_t ta = a.schedule(i * kMs);
    ASSERT_EQ(ta, b.schedule(i * kMs));
    differ += ta != c.schedule(i * kMs);
  }
  EXPECT_GT(differ, 500);
}

TEST(LinkImpairment, NoDelayNoLossIsTransparent) {
  LinkImpairment link({}, 1);
  for (int i = 0; i < 100; ++i)
    EXPECT_EQ(link.schedule(i * kMs + 3), i * kMs + 3);
}

TEST(LinkImpairment, BadParametersAreNamed) {
  EXPECT_THROW(LinkImpairment({.delay_s = -1}, 1), std::invalid_argument);
  try {
    LinkImpairment({.delay_s = 0.01, .jitter_s = 0.02}, 1);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("jitter"), std::string::npos) << e.what();
  }
  EXPECT_THROW(LinkImpairment({.drop_fraction = 1.5}, 1), std::invalid_argument);
  EXPECT_THROW(LinkImpairment({.drop_fraction = std::nan("")}, 1), std::invalid_argument);
}

TEST(DelayLine, ReleasesEachPayloadUnchangedNotBeforeItsTime) {
  DelayLine<std::vector<std::uint8_t>> line({.delay_s = 0.005, .jitter_s = 0.0}, 1);
  for (int i = 0; i < 10; ++i)
    ASSERT_TRUE(line.push(i * kMs, {static_cast<std::uint8_t>(i), 0xAB}));
  std::vector<std::uint8_t> out;
  EXPECT_FALSE(line.pop_due(5 * kMs - 1, out));
  for (int i = 0; i < 10; ++i) {
    EXPECT_EQ(line.next_release_ns(), (i + 5) * kMs);
    ASSERT_TRUE(line.pop_due((i + 5) * kMs, out));
    EXPECT_EQ(out, (std::vector<std::uint8_t>{static_cast<std::uint8_t>(i), 0xAB}));
    EXPECT_FALSE(line.pop_due((i + 5) * kMs, out));
  }
  EXPECT_EQ(line.next_release_ns(), INT64_MAX);
}

// --- the program, over udpm on this host ---------------------------------

struct Received {
  std::vector<std::int64_t> delays_ns;  // arrival - the send time written in the payload
  std::vector<std::uint32_t> ids;
  int corrupt = 0;
};

void on_raw(const lcm::ReceiveBuffer* rb, const std::string&, Received* r) {
  // Payload: id (4 B), send time (8 B), then 100 bytes of a pattern of id.
  if (rb->data_size != 112) {
    ++r->corrupt;
    return;
  }
  const auto* p = static_cast<const std::uint8_t*>(rb->data);
  std::uint32_t id = 0;
  std::int64_t sent = 0;
  std::memcpy(&id, p, 4);
  std::memcpy(&sent, p + 4, 8);
  for (int i = 0; i < 100; ++i)
    if (p[12 + i] != static_cast<std::uint8_t>(id * 7 + static_cast<std::uint32_t>(i))) {
      ++r->corrupt;
      return;
    }
  r->ids.push_back(id);
  r->delays_ns.push_back(realtime::monotonic_now_ns() - sent);
}

TEST(LcmDelayRelay, DelaysAndDropsEachDirectionAndForwardsBytesUnchanged) {
  const std::string slave_url = "udpm://239.255.76.67:7741?ttl=0";
  const std::string server_url = "udpm://239.255.76.67:7742?ttl=0";
  std::vector<std::string> args{LCM_DELAY_RELAY_BIN,
                                "--slave-url",
                                slave_url,
                                "--server-url",
                                server_url,
                                "--to-server-delay-ms",
                                "30",
                                "--to-server-jitter-ms",
                                "6",
                                "--to-server-drop",
                                "0.1",
                                "--to-slave-delay-ms",
                                "10",
                                "--to-slave-drop",
                                "0",
                                "--seed",
                                "3",
                                "--duration",
                                "20"};
  std::vector<char*> argv;
  for (auto& a : args)
    argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, argv[0], nullptr, nullptr, argv.data(), environ), 0);

  lcm::LCM slave(slave_url), server(server_url);
  ASSERT_TRUE(slave.good() && server.good());
  Received at_server, at_slave, stray;
  server.subscribeFunction<Received*>("T21_SLAVE_STATE", on_raw, &at_server);
  slave.subscribeFunction<Received*>("T21_MASTER_COMMAND", on_raw, &at_slave);
  server.subscribeFunction<Received*>("T21_OTHER", on_raw, &stray);
  std::atomic<bool> done{false};
  std::thread rx([&] {
    while (!done.load()) {  // both sockets at once: neither waits behind the other
      pollfd fds[2] = {{server.getFileno(), POLLIN, 0}, {slave.getFileno(), POLLIN, 0}};
      if (poll(fds, 2, 5) <= 0) continue;
      if (fds[0].revents & POLLIN) server.handleTimeout(0);
      if (fds[1].revents & POLLIN) slave.handleTimeout(0);
    }
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // the relay subscribes

  constexpr int kN = 1000;
  std::uint8_t buf[112];
  for (std::uint32_t id = 0; id < kN; ++id) {
    const std::int64_t now = realtime::monotonic_now_ns();
    std::memcpy(buf, &id, 4);
    std::memcpy(buf + 4, &now, 8);
    for (int i = 0; i < 100; ++i)
      buf[12 + i] = static_cast<std::uint8_t>(id * 7 + static_cast<std::uint32_t>(i));
    slave.publish("T21_SLAVE_STATE", buf, sizeof buf);
    server.publish("T21_MASTER_COMMAND", buf, sizeof buf);
    slave.publish("T21_OTHER", buf, sizeof buf);  // matches no relayed channel
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(1000));
  done = true;
  rx.join();
  kill(pid, SIGTERM);
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);

  EXPECT_EQ(at_server.corrupt + at_slave.corrupt, 0) << "payloads arrive byte for byte";
  EXPECT_TRUE(stray.ids.empty()) << "only the matching channels are relayed";
  // slave -> server: 30 +- 6 ms, 10 % lost. Binomial(1000, 0.1): sd 9.5.
  const auto lost_up = kN - static_cast<int>(at_server.ids.size());
  EXPECT_GT(lost_up, 55);
  EXPECT_LT(lost_up, 150);
  ASSERT_FALSE(at_server.delays_ns.empty());
  const auto [lo, hi] = std::minmax_element(at_server.delays_ns.begin(), at_server.delays_ns.end());
  EXPECT_GE(*lo, 24 * kMs) << "never earlier than delay - jitter";
  EXPECT_LT(*lo, 30 * kMs) << "jitter spreads the delays";
  // Upper bound: delay + jitter, plus scheduling slack on a busy 2-core machine.
  EXPECT_LE(*hi, 36 * kMs + 80 * kMs);
  for (std::size_t i = 1; i < at_server.ids.size(); ++i)
    EXPECT_LT(at_server.ids[i - 1], at_server.ids[i]) << "order kept";
  // server -> slave: 10 ms, nothing lost.
  EXPECT_GE(at_slave.ids.size(), static_cast<std::size_t>(kN - 2)) << "no drop configured";
  ASSERT_FALSE(at_slave.delays_ns.empty());
  const auto [lo2, hi2] = std::minmax_element(at_slave.delays_ns.begin(), at_slave.delays_ns.end());
  EXPECT_GE(*lo2, 10 * kMs);
  EXPECT_LE(*hi2, 10 * kMs + 80 * kMs);
}

}  // namespace
}  // namespace tsmh::delay_relay
