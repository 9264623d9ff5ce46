// One master, one slave (docs/bridge.md, "Sessions"), end to end with the
// real haptic-server (simulated console) and virtual-slave over udpm on this
// host, all keyed with the test key: two pairs on one channel, a second
// slave joining, replays into a restarted slave and into a restarted server,
// the deliberate restart of the server, a CALIBRATION_REQUEST from a third
// process, and an unauthenticated flood that cannot end a session. The test
// listens raw (a tap: trailers included) and decodes what it needs.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <tsmh/haptic_status_t.hpp>
#include <tsmh/slave_state_t.hpp>
#include <vector>

#include "bridge/codec.hpp"
#include "bridge/link_auth.hpp"
#include "realtime/clock.hpp"
#include "scratch_dir_fixture.hpp"
#include "server_child.hpp"
#include "test_link_key.hpp"
#include "wait_until.hpp"

namespace tsmh::haptics {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::Child;

// Its own port: nothing here reaches other tests' sockets.
std::string url() {
  return "udpm://239.255.76.67:7751?ttl=0";
}

std::string unique_prefix() {
  static int n = 0;
  return "S" + std::to_string(getpid()) + "_" + std::to_string(++n) + "_";
}

std::uint64_t u64_at(const std::uint8_t* p) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i)
    v = (v << 8) | p[i];
  return v;
}

/// One raw message as the tap saw it.
struct Seen {
  std::string channel;
  std::vector<std::uint8_t> bytes;
  std::int64_t at_ns = 0;
  std::uint64_t sender = 0;  ///< trailer's sender id (0: no v2 trailer)
  std::uint64_t names = 0;   ///< trailer's peer id
  std::size_t payload() const {
    return bytes.size() - (sender != 0 ? bridge::kAuthTrailerBytes : 0);
  }
};

/// Records every message on the channels matching `regex`.
class Tap {
 public:
  explicit Tap(const std::string& regex) : lcm_(url()) {
    lcm_.subscribeFunction<Tap*>(
        regex,
        [](const lcm::ReceiveBuffer* rb, const std::string& channel, Tap* self) {
          Seen s;
          s.channel = channel;
          const auto* p = static_cast<const std::uint8_t*>(rb->data);
          s.bytes.assign(p, p + rb->data_size);
          s.at_ns = realtime::monotonic_now_ns();
          if (bridge::auth_trailer_size(p, rb->data_size) == bridge::kAuthTrailerBytes) {
            const std::uint8_t* t = p + rb->data_size - bridge::kAuthTrailerBytes;
            s.sender = u64_at(t + 8);
            s.names = u64_at(t + 32);
          }
          const std::lock_guard lock(self->mutex_);
          self->seen_.push_back(std::move(s));
        },
        this);
    thread_ = std::thread([this] {
      while (running_)
        lcm_.handleTimeout(10);
    });
  }
  ~Tap() {
    running_ = false;
    thread_.join();
  }
  Tap(const Tap&) = delete;
  Tap& operator=(const Tap&) = delete;

  std::vector<Seen> seen() {
    const std::lock_guard lock(mutex_);
    return seen_;
  }
  /// Sender ids seen on `channel`.
  std::set<std::uint64_t> senders(const std::string& channel) {
    std::set<std::uint64_t> out;
    for (const auto& s : seen())
      if (s.channel == channel && s.sender != 0) out.insert(s.sender);
    return out;
  }

 private:
  lcm::LCM lcm_;
  std::mutex mutex_;
  std::vector<Seen> seen_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

tsmh::slave_state_t state_of(const Seen& s) {
  tsmh::slave_state_t m;
  m.decode(s.bytes.data(), 0, static_cast<int>(s.payload()));
  return m;
}

tsmh::haptic_status_t status_of(const Seen& s) {
  tsmh::haptic_status_t m;
  m.decode(s.bytes.data(), 0, static_cast<int>(s.payload()));
  return m;
}

/// The last HAPTIC_STATUS of one server (by sender id).
std::optional<tsmh::haptic_status_t> last_status(Tap& tap, const std::string& channel,
                                                 std::uint64_t server) {
  std::optional<tsmh::haptic_status_t> out;
  for (const auto& s : tap.seen())
    if (s.channel == channel && s.sender == server) out = status_of(s);
  return out;
}

// Polled every 5ms.
template <class Pred>
bool wait_until(Pred done, std::chrono::milliseconds timeout) {
  return test::wait_until(done, timeout, 5ms);
}

class ServerSessions : public test::ScratchDirTest {
 protected:
  ServerSessions() : ScratchDirTest("tsmh-server-sessions") {}

  /// The simulated console palpating (dead-man held), naive feedback.
  fs::path config(const std::string& prefix, const std::string& name = "server.yaml") {
    const fs::path p = dir_ / name;
    std::ofstream(p) << "rate_hz: 1000\nfeedback: naive\n"
                     << "device: {driver: sim, settings: {scenario: palpate, stale_timeout_ms: "
                        "500, command_timeout_ms: 500}}\n"
                     << "safety: {device_stale_fault_ms: 500}\n"
                     << "lcm: {prefix: " << prefix << "}\n"
                     << "realtime: {sched_fifo: false, lock_memory: false, "
                        "cpu_dma_latency: false}\n"
                     << "joints:\n"
                     << "  - {params: paper, max_torque_nm: 0.3}\n"
                     << "  - {params: paper, max_torque_nm: 0.3}\n";
    return p;
  }
  std::unique_ptr<Child> server(const std::string& prefix, const std::string& name,
                                double seconds = 30) {
    return std::make_unique<Child>(
        std::vector<std::string>{TSMH_HAPTIC_SERVER, "--config",
                                 config(prefix, name + ".yaml").string(), "--lcm-url", url(),
                                 "--duration", std::to_string(seconds), "--quiet"},
        dir_ / (name + ".log"));
  }
  std::unique_ptr<Child> slave(const std::string& prefix, const std::string& name) {
    return std::make_unique<Child>(
        std::vector<std::string>{TSMH_VIRTUAL_SLAVE, "--lcm-url", url(), "--prefix", prefix,
                                 "--tissue", "nodule"},
        dir_ / (name + ".log"));
  }
  void SetUp() override {
    ScratchDirTest::SetUp();
    ASSERT_NE(test::test_link_key(), nullptr) << "ctest sets TSMH_LINK_KEY for these tests";
  }
};

/// A session is running: the server's HAPTIC_STATUS says ENABLED and the
/// slave follows (SLAVE_STATE status bit 0).
bool session_running(Tap& tap, const std::string& prefix) {
  bool enabled = false, following = false;
  const auto seen = tap.seen();
  for (auto it = seen.rbegin(); it != seen.rend() && !(enabled && following); ++it) {
    if (it->channel == prefix + "HAPTIC_STATUS") enabled = enabled || status_of(*it).state == 1;
    if (it->channel == prefix + "SLAVE_STATE")
      following = following || (state_of(*it).status & 1) != 0;
  }
  return enabled && following;
}

// Two demos with one key on one channel steered each other's slave (the
// servers ended "ENABLED; exit 0"). Now pair B's arrival ends both sessions:
// servers A and B and slave A exit 4, the servers end in FAULT (flag 14)
// with zero torque, slave A holds from pair B's first message on, and slave
// B (arriving when nobody can be its master any more) never follows anything.
TEST_F(ServerSessions, TwoPairsWithOneKeyOnOneChannelBothEndInFault) {
  const std::string prefix = unique_prefix();
  Tap tap(prefix + ".*");
  auto slave_a = slave(prefix, "slave-a");
  auto server_a = server(prefix, "server-a");
  ASSERT_TRUE(wait_until([&] { return session_running(tap, prefix); }, 10s))
      << server_a->log() << slave_a->log();
  const auto servers_a = tap.senders(prefix + "MASTER_COMMAND");
  const auto slaves_a = tap.senders(prefix + "SLAVE_STATE");
  ASSERT_EQ(servers_a.size(), 1U);
  ASSERT_EQ(slaves_a.size(), 1U);
  const std::int64_t b_started = realtime::monotonic_now_ns();
  auto server_b = server(prefix, "server-b");
  auto slave_b = slave(prefix, "slave-b");
  std::string what;
  for (auto* c : {server_a.get(), server_b.get(), slave_a.get()}) {
    EXPECT_EQ(c->wait(10s, &what), 4) << what << "\n" << c->log();
  }
  EXPECT_NE(server_a->log().find("another slave session on the link"), std::string::npos)
      << server_a->log();
  EXPECT_NE(server_b->log().find("another slave session on the link"), std::string::npos)
      << server_b->log();
  EXPECT_NE(slave_a->log().find("FAULT: another master session"), std::string::npos)
      << slave_a->log();
  // Both servers' last status: FAULT, flag 14, zero torque.
  const auto servers = tap.senders(prefix + "HAPTIC_STATUS");
  EXPECT_EQ(servers.size(), 2U);
  for (const auto& s : servers) {
    const auto st = last_status(tap, prefix + "HAPTIC_STATUS", s);
    ASSERT_TRUE(st.has_value());
    EXPECT_EQ(st->state, 2) << "server " << s;
    EXPECT_NE(st->flags & (1 << 14), 0) << "server " << s;
    for (double t : st->torque_cmd)
      EXPECT_EQ(t, 0.0) << "server " << s;
  }
  // Slave B never followed a command.
  for (const auto& s : tap.seen())
    if (s.channel == prefix + "SLAVE_STATE" && slaves_a.count(s.sender) == 0) {
      EXPECT_EQ(state_of(s).status & 1, 0) << "slave B followed a command";
    }
  slave_b->signal(SIGINT);
  slave_b->wait(5s);
  // No command of pair B moved slave A: from the first message of pair B on,
  // slave A follows nothing (status bit 0 never set once pair B's first
  // MASTER_COMMAND reached it) and its motor angle stays where it was held.
  const std::uint64_t a = *slaves_a.begin();
  std::int64_t b_first_ns = 0;
  for (const auto& s : tap.seen())
    if (s.channel == prefix + "MASTER_COMMAND" && servers_a.count(s.sender) == 0 &&
        s.at_ns >= b_started) {
      b_first_ns = s.at_ns;
      break;
    }
  ASSERT_GT(b_first_ns, 0) << "server B never published";
  int following_after = 0, samples_after = 0;
  double lo = 1e9, hi = -1e9;
  for (const auto& s : tap.seen()) {
    if (s.channel != prefix + "SLAVE_STATE" || s.sender != a) continue;
    if (s.at_ns < b_first_ns + 5'000'000) continue;  // 5 ms for slave A to hear it
    const auto m = state_of(s);
    ++samples_after;
    following_after += (m.status & 1) != 0;
    if (s.at_ns > b_first_ns + 1'000'000'000) {  // settled on the held reference
      lo = std::min(lo, m.x_in[0]);
      hi = std::max(hi, m.x_in[0]);
    }
  }
  EXPECT_EQ(following_after, 0) << "slave A followed commands after pair B appeared";
  if (hi >= lo) {
    EXPECT_LT(hi - lo, 0.03) << "slave A moved after pair B appeared";
  }
  (void)samples_after;
}

// A second keyed virtual-slave joining a running session doubled the
// torque. Now the server refuses it, goes into FAULT with zero torque, tells
// its slave to hold and exits 4 naming the cause.
TEST_F(ServerSessions, ASecondKeyedSlaveJoiningEndsTheSessionWithZeroTorque) {
  const std::string prefix = unique_prefix();
  Tap tap(prefix + ".*");
  auto slave_a = slave(prefix, "slave-a");
  auto srv = server(prefix, "server");
  ASSERT_TRUE(wait_until([&] { return session_running(tap, prefix); }, 10s))
      << srv->log() << slave_a->log();
  auto slave_b = slave(prefix, "slave-b");
  std::string what;
  EXPECT_EQ(srv->wait(8s, &what), 4) << what << "\n" << srv->log();
  EXPECT_NE(srv->log().find("ended in FAULT: another slave session on the link"), std::string::npos)
      << srv->log();
  const auto server_id = *tap.senders(prefix + "MASTER_COMMAND").begin();
  const auto st = last_status(tap, prefix + "HAPTIC_STATUS", server_id);
  ASSERT_TRUE(st.has_value());
  EXPECT_EQ(st->state, 2);
  EXPECT_NE(st->flags & (1 << 14), 0);
  EXPECT_GT(st->slave_rejected, 0);
  for (double t : st->torque_cmd)
    EXPECT_EQ(t, 0.0);
  // Its last command told the slave to hold.
  std::optional<bridge::MasterCommandSample> last;
  for (const auto& s : tap.seen())
    if (s.channel == prefix + "MASTER_COMMAND" && s.sender == server_id) {
      bridge::MasterCommandSample c;
      bridge::Decoder<bridge::MasterCommandSample> decoder;
      if (!decoder.decode(s.bytes.data(), s.payload(), c)) last = c;
    }
  ASSERT_TRUE(last.has_value());
  EXPECT_FALSE(last->enable);
  slave_a->signal(SIGINT);
  slave_b->signal(SIGINT);
  slave_a->wait(5s);
  slave_b->wait(5s);
}

// A replay into a slave restarted within 2 s moved it (997 of 997 replayed
// commands accepted). The restarted slave has a new id: the recorded
// commands name the old one, so none is used (0 accepted, no motion).
TEST_F(ServerSessions, ReplayedCommandsIntoARestartedSlaveMoveNothing) {
  const std::string prefix = unique_prefix();
  Tap tap(prefix + ".*");
  auto slave1 = slave(prefix, "slave-1");
  auto srv = server(prefix, "server");
  ASSERT_TRUE(wait_until([&] { return session_running(tap, prefix); }, 10s))
      << srv->log() << slave1->log();
  std::this_thread::sleep_for(700ms);
  // The last 600 ms of commands, recorded as a rogue on the network would.
  std::vector<std::vector<std::uint8_t>> recorded;
  const std::int64_t now = realtime::monotonic_now_ns();
  for (const auto& s : tap.seen())
    if (s.channel == prefix + "MASTER_COMMAND" && s.at_ns > now - 600'000'000)
      recorded.push_back(s.bytes);
  ASSERT_GT(recorded.size(), 200U);
  srv->signal(SIGKILL);
  slave1->signal(SIGKILL);
  srv->wait(2s);
  slave1->wait(2s);
  const std::int64_t restarted_ns = realtime::monotonic_now_ns();
  auto slave2 = slave(prefix, "slave-2");
  ASSERT_TRUE(wait_until(
      [&] {
        for (const auto& s : tap.seen())
          if (s.channel == prefix + "SLAVE_STATE" && s.at_ns > restarted_ns) return true;
        return false;
      },
      3s));
  // Replay them all, at 1 kHz, still inside the 2 s freshness window.
  lcm::LCM lcm(url());
  for (const auto& m : recorded) {
    lcm.publish(prefix + "MASTER_COMMAND", m.data(), static_cast<unsigned>(m.size()));
    std::this_thread::sleep_for(1ms);
  }
  std::string what;
  const int rc = slave2->wait(5s, &what);
  if (rc == -1) {
    slave2->signal(SIGINT);
    slave2->wait(3s);
  }
  const std::string log = slave2->log();
  EXPECT_NE(log.find("MASTER_COMMAND accepted 0,"), std::string::npos) << log;
  EXPECT_EQ(rc, 4) << "the recording names another session: FAULT\n" << what << "\n" << log;
  // And it never moved: every SLAVE_STATE of the restarted slave holds.
  for (const auto& s : tap.seen())
    if (s.channel == prefix + "SLAVE_STATE" && s.at_ns > restarted_ns) {
      const auto m = state_of(s);
      EXPECT_EQ(m.status & 1, 0) << "the restarted slave followed a replayed command";
    }
}

// The same the other way: SLAVE_STATE recorded from a session, replayed into
// a restarted server within 2 s: nothing is rendered (no SLAVE_STATE used).
TEST_F(ServerSessions, ReplayedSlaveStateIntoARestartedServerRendersNothing) {
  const std::string prefix = unique_prefix();
  Tap tap(prefix + ".*");
  auto slave1 = slave(prefix, "slave-1");
  auto srv1 = server(prefix, "server-1");
  ASSERT_TRUE(wait_until([&] { return session_running(tap, prefix); }, 10s))
      << srv1->log() << slave1->log();
  std::this_thread::sleep_for(700ms);
  std::vector<std::vector<std::uint8_t>> recorded;
  const std::int64_t now = realtime::monotonic_now_ns();
  for (const auto& s : tap.seen())
    if (s.channel == prefix + "SLAVE_STATE" && s.at_ns > now - 600'000'000)
      recorded.push_back(s.bytes);
  ASSERT_GT(recorded.size(), 200U);
  slave1->signal(SIGKILL);
  srv1->signal(SIGKILL);
  slave1->wait(2s);
  srv1->wait(2s);
  const std::int64_t restarted_ns = realtime::monotonic_now_ns();
  auto srv2 = server(prefix, "server-2", 3);
  ASSERT_TRUE(wait_until(
      [&] {
        for (const auto& s : tap.seen())
          if (s.channel == prefix + "HAPTIC_STATUS" && s.at_ns > restarted_ns) return true;
        return false;
      },
      3s))
      << srv2->log();
  lcm::LCM lcm(url());
  for (const auto& m : recorded) {
    lcm.publish(prefix + "SLAVE_STATE", m.data(), static_cast<unsigned>(m.size()));
    std::this_thread::sleep_for(1ms);
  }
  std::string what;
  const int rc = srv2->wait(6s, &what);
  EXPECT_EQ(rc, 4) << "the recording names another session: FAULT\n" << what << "\n" << srv2->log();
  EXPECT_NE(srv2->log().find("0 accepted"), std::string::npos) << srv2->log();
  EXPECT_NE(srv2->log().find("other_session"), std::string::npos) << srv2->log();
  for (const auto& s : tap.seen())
    if (s.channel == prefix + "HAPTIC_STATUS" && s.at_ns > restarted_ns) {
      for (double t : status_of(s).torque_cmd)
        EXPECT_EQ(t, 0.0) << "torque rendered from a replayed SLAVE_STATE";
    }
}

// The deliberate restart: a server that stops (a stop signal) says goodbye;
// the slave holds and serves the next server at once, without a FAULT.
// After a server that died (SIGKILL) the slave serves the next one once the
// old one has been silent for the session timeout (1 s).
// For a failure message: who named whom on the session channels, when.
std::string who_named_whom(Tap& tap, const std::string& prefix) {
  struct Pair {
    std::uint64_t n = 0;
    std::int64_t first = 0, last = 0;
  };
  std::map<std::string, Pair> pairs;
  const auto seen = tap.seen();
  const std::int64_t t0 = seen.empty() ? 0 : seen.front().at_ns;
  for (const auto& s : seen) {
    if (s.channel != prefix + "SLAVE_STATE" && s.channel != prefix + "MASTER_COMMAND") continue;
    char key[128];
    std::snprintf(key, sizeof key, "%s %016llx names %016llx", s.channel.c_str(),
                  static_cast<unsigned long long>(s.sender),
                  static_cast<unsigned long long>(s.names));
    auto& p = pairs[key];
    if (p.n++ == 0) p.first = s.at_ns - t0;
    p.last = s.at_ns - t0;
  }
  std::string out;
  for (const auto& [k, p] : pairs)
    out += k + ": " + std::to_string(p.n) + " from " + std::to_string(p.first / 1'000'000) +
           " to " + std::to_string(p.last / 1'000'000) + " ms\n";
  return out;
}

TEST_F(ServerSessions, ARestartedServerIsServedAfterGoodbyeOrSilence) {
  const std::string prefix = unique_prefix();
  Tap tap(prefix + ".*");
  auto sl = slave(prefix, "slave");
  // The slave says so each time it binds a master; SLAVE_STATE's "controller
  // enabled" bit alone cannot tell (it stays set while the slave holds between
  // masters).
  auto binds = [&] {
    const std::string log = sl->log();
    std::size_t n = 0;
    for (auto at = log.find("session: following master"); at != std::string::npos;
         at = log.find("session: following master", at + 1))
      ++n;
    return n;
  };
  auto srv1 = server(prefix, "server-1");
  ASSERT_TRUE(wait_until([&] { return session_running(tap, prefix) && binds() == 1; }, 10s))
      << srv1->log() << sl->log();
  srv1->signal(SIGINT);
  EXPECT_EQ(srv1->wait(5s), 0) << srv1->log();
  auto srv2 = server(prefix, "server-2");  // at once: no wait for a timeout
  ASSERT_TRUE(wait_until([&] { return binds() == 2; }, 10s))
      << srv2->log() << sl->log() << who_named_whom(tap, prefix);
  EXPECT_TRUE(sl->running()) << sl->log();
  // Now kill it: no goodbye. The slave holds and takes the next server after 1 s.
  srv2->signal(SIGKILL);
  srv2->wait(2s);
  std::this_thread::sleep_for(1500ms);
  auto srv3 = server(prefix, "server-3", 3);
  ASSERT_TRUE(wait_until([&] { return binds() == 3; }, 10s)) << srv3->log() << sl->log();
  EXPECT_EQ(srv3->wait(8s), 0) << srv3->log();
  EXPECT_TRUE(sl->running()) << sl->log();
  sl->signal(SIGINT);
  EXPECT_EQ(sl->wait(5s), 0) << sl->log();
  EXPECT_EQ(binds(), 3U) << sl->log();
  EXPECT_EQ(sl->log().find("FAULT"), std::string::npos) << sl->log();
}

// CALIBRATION_REQUEST may come from any process with the key (a console):
// it is not a session channel. The request is honoured and the session
// goes on.
TEST_F(ServerSessions, CalibrationRequestFromAThirdProcessStillWorks) {
  const std::string prefix = unique_prefix();
  Tap tap(prefix + ".*");
  auto sl = slave(prefix, "slave");
  auto srv = server(prefix, "server", 6);
  ASSERT_TRUE(wait_until([&] { return session_running(tap, prefix); }, 10s))
      << srv->log() << sl->log();
  lcm::LCM lcm(url());
  const auto signer = test::test_signer();
  bridge::CalibrationRequestSample req;
  req.utime = realtime::monotonic_utime();
  req.seq = 1;
  req.num_joints = 2;
  req.recalibrate = {true, true};
  ASSERT_EQ(bridge::publish_sample(lcm, prefix + "CALIBRATION_REQUEST", req, signer.get()), 0);
  const auto server_id = *tap.senders(prefix + "MASTER_COMMAND").begin();
  EXPECT_TRUE(wait_until(
      [&] {
        const auto st = last_status(tap, prefix + "HAPTIC_STATUS", server_id);
        return st && st->calibration_state != 0;
      },
      3s))
      << "the request from a third process was not taken\n"
      << srv->log();
  EXPECT_EQ(srv->wait(10s), 0) << srv->log();
  sl->signal(SIGINT);
  EXPECT_EQ(sl->wait(5s), 0) << sl->log();
}

// Nobody without the key can end a session: a flood of unsigned and
// wrongly signed SLAVE_STATE and MASTER_COMMAND is refused and counted, and
// server and slave end cleanly.
TEST_F(ServerSessions, AnUnauthenticatedFloodCannotEndASession) {
  const std::string prefix = unique_prefix();
  Tap tap(prefix + "HAPTIC_STATUS|" + prefix + "SLAVE_STATE");
  auto sl = slave(prefix, "slave");
  auto srv = server(prefix, "server", 5);
  ASSERT_TRUE(wait_until([&] { return session_running(tap, prefix); }, 10s))
      << srv->log() << sl->log();
  std::atomic<bool> flooding{true};
  std::atomic<long> sent{0};
  std::thread rogue([&] {
    lcm::LCM lcm(url());
    const bridge::MessageSigner wrong_key(
        std::make_shared<const bridge::LinkKey>(bridge::LinkKey::generate()));
    for (std::int64_t seq = 1; flooding; ++seq) {
      auto* signer = seq % 2 == 0 ? const_cast<bridge::MessageSigner*>(&wrong_key) : nullptr;
      bridge::SlaveStateSample s;
      s.utime = realtime::monotonic_utime();
      s.seq = seq;
      s.num_joints = 2;
      bridge::publish_sample(lcm, prefix + "SLAVE_STATE", s, signer);
      bridge::MasterCommandSample c;
      c.utime = s.utime;
      c.seq = seq;
      c.num_joints = 2;
      c.enable = true;
      c.position_ref = {0.5, -0.5};
      bridge::publish_sample(lcm, prefix + "MASTER_COMMAND", c, signer);
      sent += 2;
      std::this_thread::sleep_for(200us);
    }
  });
  std::string what;
  const int rc = srv->wait(10s, &what);
  flooding = false;
  rogue.join();
  EXPECT_GT(sent.load(), 2000);
  EXPECT_EQ(rc, 0) << what << "\n" << srv->log();
  EXPECT_NE(srv->log().find("rejected by reason: unauthenticated "), std::string::npos)
      << srv->log();
  sl->signal(SIGINT);
  EXPECT_EQ(sl->wait(5s), 0) << sl->log();
  EXPECT_EQ(sl->log().find("FAULT"), std::string::npos) << sl->log();
}

}  // namespace
}  // namespace tsmh::haptics
