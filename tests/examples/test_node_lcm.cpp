// The real-time node over real LCM (udpm on this host): it follows
// MASTER_COMMAND, publishes SLAVE_STATE and SLAVE_TRUTH with matching seq,
// and holds position when the commands stop. Skips (with the fix) where the
// host has no multicast route.

#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <ctime>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <string>
#include <tsmh/master_command_t.hpp>
#include <tsmh/slave_state_t.hpp>
#include <tsmh/slave_truth_t.hpp>
#include <vector>

#include "bridge/link_auth.hpp"
#include "bridge/link_security.hpp"
#include "realtime/clock.hpp"
#include "session_answer.hpp"

namespace {

using tsmh::bridge::LinkKey;
using tsmh::bridge::MessageSigner;

// The node finds the link key through TSMH_LINK_KEY (set by ctest); the
// test's commands are signed with it, as haptic-server's are.
std::shared_ptr<const LinkKey> test_key() {
  const char* file = std::getenv(tsmh::bridge::kLinkKeyEnv);
  if (file == nullptr || file[0] == '\0') return nullptr;
  return std::make_shared<const LinkKey>(LinkKey::load(file));
}

// The encoded message followed by its trailer (no trailer without a signer).
std::vector<std::uint8_t> encode(const tsmh::master_command_t& m, const std::string& channel,
                                 MessageSigner* signer) {
  const int size = m.getEncodedSize();
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  m.encode(bytes.data(), 0, size);
  if (signer != nullptr) {
    bytes.resize(bytes.size() + tsmh::bridge::kAuthTrailerBytes);
    signer->sign(channel, bytes.data(), static_cast<std::size_t>(size), bytes.data() + size);
  }
  return bytes;
}

void publish(lcm::LCM& lcm, const std::string& channel, const std::vector<std::uint8_t>& bytes) {
  lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
}

double monotonic_s() {
  return 1e-9 * static_cast<double>(tsmh::realtime::monotonic_now_ns());
}

struct Listener {
  tsmh::slave_state_t last{};
  long states = 0;
  std::map<std::int64_t, double> truth_x_out;  // seq -> true joint angle
  double last_receive_s = 0.0;
  void on_state(const lcm::ReceiveBuffer*, const std::string&, const tsmh::slave_state_t* m) {
    last = *m;
    ++states;
    last_receive_s = monotonic_s();
  }
  void on_truth(const lcm::ReceiveBuffer*, const std::string&, const tsmh::slave_truth_t* m) {
    if (m->num_joints == 2) truth_x_out[m->seq] = m->x_out[0];
  }
};

// Handles incoming messages for `seconds`, calling `each()` about every 2 ms.
template <class F>
void pump(lcm::LCM& lcm, double seconds, F each) {
  const double end = monotonic_s() + seconds;
  double next = monotonic_s();
  while (monotonic_s() < end) {
    if (monotonic_s() >= next) {
      each();
      next += 0.002;
    }
    pollfd p{lcm.getFileno(), POLLIN, 0};
    if (poll(&p, 1, 1) > 0) lcm.handle();
  }
}

// The start-up every standalone node shares (bridge/node_link.hpp): no key
// on a URL that reaches the network is refused with exit 2 and the way to
// make one; a URL the strict parser refuses likewise.
TEST(Node, RefusesToRunUnkeyedOnANetworkUrlLikeEveryNode) {
  char home[] = "/tmp/vs_nokey_XXXXXX";
  ASSERT_NE(mkdtemp(home), nullptr);
  auto run = [&](const char* url) {
    const std::string cmd = std::string("env -u TSMH_LINK_KEY -u XDG_CONFIG_HOME HOME=") + home +
                            " " + VIRTUAL_SLAVE_BIN + " --duration 1 --lcm-url '" + url + "' 2>&1";
    FILE* p = popen(cmd.c_str(), "r");
    std::string out;
    char buf[512];
    while (p != nullptr && std::fgets(buf, sizeof buf, p) != nullptr)
      out += buf;
    const int status = p != nullptr ? pclose(p) : -1;
    return std::make_pair(WIFEXITED(status) ? WEXITSTATUS(status) : -1, out);
  };
  const auto [network_rc, network] = run("udpm://239.255.76.67:7667?ttl=1");
  EXPECT_EQ(network_rc, 2) << network;
  EXPECT_NE(network.find("virtual-slave: error:"), std::string::npos) << network;
  EXPECT_NE(network.find("tsm-link keygen"), std::string::npos) << network;
  const auto [bad_rc, bad] = run("udpm://239.255.76.67:7667?ttl=0&ttl=1");
  EXPECT_EQ(bad_rc, 2) << bad;
  rmdir(home);
}

}  // namespace

TEST(Node, FollowsCommandsPublishesStateAndTruthAndHoldsWhenCommandsStop) {
  lcm::LCM lcm;  // LCM_DEFAULT_URL or LCM's default, like the node
  if (!lcm.good())
    GTEST_SKIP() << "LCM cannot start here (no multicast route?): ip link set lo multicast on; "
                    "ip route add 224.0.0.0/4 dev lo";
  const std::string prefix = "VSTEST" + std::to_string(::getpid()) + "_";

  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    execl(VIRTUAL_SLAVE_BIN, VIRTUAL_SLAVE_BIN, "--duration", "5", "--prefix", prefix.c_str(),
          "--tissue", "none", static_cast<char*>(nullptr));
    _exit(127);
  }

  Listener listener;
  lcm.subscribe(prefix + "SLAVE_STATE", &Listener::on_state, &listener);
  lcm.subscribe(prefix + "SLAVE_TRUTH", &Listener::on_truth, &listener);
  pump(lcm, 1.0, [] {});
  ASSERT_GT(listener.states, 100) << "no SLAVE_STATE from the node";
  EXPECT_EQ(listener.last.num_joints, 2);
  EXPECT_EQ(listener.last.status & 2, 2) << "holding before any command";
  EXPECT_NEAR(listener.last.radius_m[0], 0.01, 1e-12);
  EXPECT_NEAR(static_cast<double>(listener.last.utime) * 1e-6, listener.last_receive_s, 0.5)
      << "utime is CLOCK_MONOTONIC microseconds";

  // Command 0.3 / -0.2 rad for 1.5 s.
  tsmh::master_command_t cmd{};
  cmd.num_joints = 2;
  cmd.position_ref = {0.3, -0.2};
  cmd.enable = true;
  const auto key = test_key();
  ASSERT_NE(key, nullptr) << "ctest sets TSMH_LINK_KEY";
  MessageSigner signer(key);
  // The commander answers the node's session, as the server does.
  const tsmh::haptics::test::SessionAnswer answer("", prefix + "SLAVE_STATE", key, &signer);
  const std::string channel = prefix + "MASTER_COMMAND";
  pump(lcm, 1.5, [&] {
    cmd.utime = static_cast<std::int64_t>(monotonic_s() * 1e6);
    ++cmd.seq;
    publish(lcm, channel, encode(cmd, channel, &signer));
  });
  EXPECT_EQ(listener.last.status & 1, 1) << "following";
  EXPECT_NEAR(listener.last.x_out[0], 0.3, 0.01);
  EXPECT_NEAR(listener.last.x_out[1], -0.2, 0.01);

  // Silence: the node holds where it is.
  pump(lcm, 0.5, [] {});
  EXPECT_EQ(listener.last.status & 2, 2) << "holding after the commands stopped";
  const double held = listener.last.x_out[0];
  double lo = held, hi = held;
  pump(lcm, 1.0, [&] {
    lo = std::min(lo, listener.last.x_out[0]);
    hi = std::max(hi, listener.last.x_out[0]);
  });
  EXPECT_LT(hi - lo, 0.003);
  EXPECT_NEAR(held, 0.3, 0.01);
  // SLAVE_TRUTH carries the same seq as SLAVE_STATE of the same tick.
  EXPECT_TRUE(listener.truth_x_out.count(listener.last.seq) == 1 ||
              listener.truth_x_out.count(listener.last.seq - 1) == 1);

  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

// Commands without the link key, with another key, or replayed
// (an authentic recording sent again) never move the node; the
// authenticated commander does.
TEST(Node, OnlyAuthenticatedCommandsMoveIt) {
  lcm::LCM lcm;
  if (!lcm.good())
    GTEST_SKIP() << "LCM cannot start here (no multicast route?): ip link set lo multicast on; "
                    "ip route add 224.0.0.0/4 dev lo";
  const auto key = test_key();
  ASSERT_NE(key, nullptr) << "ctest sets TSMH_LINK_KEY";
  const std::string prefix = "VSAUTH" + std::to_string(::getpid()) + "_";
  const std::string channel = prefix + "MASTER_COMMAND";

  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    execl(VIRTUAL_SLAVE_BIN, VIRTUAL_SLAVE_BIN, "--duration", "6", "--prefix", prefix.c_str(),
          "--tissue", "none", static_cast<char*>(nullptr));
    _exit(127);
  }
  Listener listener;
  lcm.subscribe(prefix + "SLAVE_STATE", &Listener::on_state, &listener);
  pump(lcm, 0.5, [] {});
  ASSERT_GT(listener.states, 100) << "no SLAVE_STATE from the node";

  tsmh::master_command_t cmd{};
  cmd.num_joints = 2;
  cmd.enable = true;
  auto next = [&](double q) {
    cmd.utime = static_cast<std::int64_t>(monotonic_s() * 1e6);
    ++cmd.seq;
    cmd.position_ref = {q, -q};
    return cmd;
  };
  // Rogues: 1 s of commands to 0.3 rad, alternately unsigned and signed with another key.
  MessageSigner rogue(std::make_shared<const LinkKey>(LinkKey::generate()));
  bool with_wrong_key = false;
  double lo = 0, hi = 0;
  auto track = [&] {
    lo = std::min(lo, listener.last.x_out[0]);
    hi = std::max(hi, listener.last.x_out[0]);
  };
  pump(lcm, 1.0, [&] {
    with_wrong_key = !with_wrong_key;
    publish(lcm, channel, encode(next(0.3), channel, with_wrong_key ? &rogue : nullptr));
    track();
  });
  EXPECT_EQ(listener.last.status & 2, 2) << "still holding: no command was accepted";
  EXPECT_LT(std::max(std::abs(lo), std::abs(hi)), 0.003) << "the node moved for a rogue";

  // The authenticated commander: 0.8 s to 0.2 rad (recorded), then 0.8 s to -0.1 rad.
  MessageSigner signer(key);
  const tsmh::haptics::test::SessionAnswer answer("", prefix + "SLAVE_STATE", key, &signer);
  std::vector<std::vector<std::uint8_t>> recorded;
  pump(lcm, 0.8, [&] {
    recorded.push_back(encode(next(0.2), channel, &signer));
    publish(lcm, channel, recorded.back());
  });
  EXPECT_NEAR(listener.last.x_out[0], 0.2, 0.01) << "follows the authenticated commander";
  pump(lcm, 0.8, [&] { publish(lcm, channel, encode(next(-0.1), channel, &signer)); });
  EXPECT_NEAR(listener.last.x_out[0], -0.1, 0.01);

  // Replay the recording (hundreds of messages: enough for the bridge's
  // ordering check to re-base on them, were they not rejected first).
  ASSERT_GT(recorded.size(), 200U);
  lo = hi = listener.last.x_out[0];
  std::size_t i = 0;
  pump(lcm, 0.8, [&] {
    publish(lcm, channel, recorded[i++ % recorded.size()]);
    track();
  });
  EXPECT_NEAR(lo, -0.1, 0.01) << "a replayed command moved the node";
  EXPECT_NEAR(hi, -0.1, 0.01) << "a replayed command moved the node";

  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}
