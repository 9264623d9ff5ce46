// Hostile message bodies against the real programs over real udpm on this
// host (ttl=0, its own port): haptic-server with the `lcm` master driver,
// external-master-adapter (with and without the link key), and
// `tsm-devices --monitor lcm`. One datagram whose num_joints claims 2^28
// joints made lcm-gen's decode() allocate gigabytes in each of them (the
// server faulted and died with SIGSEGV, its last MASTER_FORCE enable=1; the
// adapter died; the monitor hung). Each must now refuse it, count it, say
// why, keep torque within limits and end cleanly. Also: the server's
// --lcm-url moves its `lcm` device, and an ambiguous URL is refused.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <tsmh/master_force_t.hpp>
#include <tsmh/master_state_t.hpp>
#include <vector>

#include "bridge/codec.hpp"
#include "bridge/link_auth.hpp"
#include "bridge/stop_signals.hpp"
#include "realtime/clock.hpp"
#include "realtime/latest_value.hpp"
#include "scratch_dir_fixture.hpp"
#include "server_child.hpp"
#include "session_answer.hpp"
#include "slave_samples.hpp"
#include "test_link_key.hpp"
#include "wait_until.hpp"

namespace tsmh::haptics {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// Its own port (other tests use theirs); ttl=0: nothing leaves this host.
std::string url() {
  return "udpm://239.255.76.67:7761?ttl=0";
}

// TSMH_SERVER_UNDER_TEST, TSMH_ADAPTER_UNDER_TEST, TSMH_DEVICES_UNDER_TEST run
// another build's programs (e.g. from before a fix) against these tests.
std::string program(const char* built, const char* override_env) {
  const char* other = std::getenv(override_env);
  return other != nullptr && other[0] != '\0' ? other : built;
}

std::string unique_prefix() {
  static int n = 0;
  return "H" + std::to_string(getpid()) + "_" + std::to_string(++n) + "_";
}

// Polled every 2ms.
template <class Pred>
bool wait_until(Pred done, std::chrono::milliseconds timeout) {
  return test::wait_until(done, timeout, 2ms);
}

// Encodes `m`; with a signer, appends its MAC trailer (the right key).
template <class Message>
std::vector<std::uint8_t> encode(const Message& m, const std::string& channel,
                                 bridge::MessageSigner* signer) {
  const int size = m.getEncodedSize();
  std::vector<std::uint8_t> b(static_cast<std::size_t>(size) +
                              (signer ? bridge::kAuthTrailerBytes : 0));
  m.encode(b.data(), 0, size);
  if (signer) signer->sign(channel, b.data(), static_cast<std::size_t>(size), b.data() + size);
  return b;
}

// The body that crashed them: a valid 2-joint message whose num_joints
// (bytes 24..27 after the type hash, utime and seq) says 2^28.
template <class Message>
std::vector<std::uint8_t> claiming_2pow28_joints(Message m, const std::string& channel,
                                                 bridge::MessageSigner* signer) {
  const int size = m.getEncodedSize();
  std::vector<std::uint8_t> b(static_cast<std::size_t>(size));
  m.encode(b.data(), 0, size);
  const std::uint32_t n = 1u << 28;
  for (int i = 0; i < 4; ++i)
    b[24 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(n >> (24 - 8 * i));
  if (signer) {  // signed after the change: the MAC verifies, the body is hostile
    b.resize(b.size() + bridge::kAuthTrailerBytes);
    signer->sign(channel, b.data(), static_cast<std::size_t>(size), b.data() + size);
  }
  return b;
}

tsmh::master_state_t master_state(std::int64_t seq) {
  tsmh::master_state_t m{};
  m.utime = realtime::monotonic_utime();
  m.seq = seq;
  m.num_joints = 2;
  m.q.assign(2, 0.0);
  m.qd.assign(2, 0.0);
  m.buttons = 1;  // dead-man held
  return m;
}

using test::Child;

struct Force {
  bool enable = false;
  std::array<double, 2> torque{};
};

/// The newest MASTER_FORCE and the largest |torque| ever seen on a channel.
class ForceListener {
 public:
  explicit ForceListener(const std::string& channel) : lcm_(url()) {
    lcm_.subscribe(channel, &ForceListener::on_force, this);
    thread_ = std::thread([this] {
      while (running_)
        lcm_.handleTimeout(10);
    });
  }
  ~ForceListener() {
    running_ = false;
    thread_.join();
  }
  Force newest() const {
    Force f;
    cell_.load(f);
    return f;
  }
  double peak() const { return peak_.load(); }
  std::uint64_t count() const { return count_.load(); }

 private:
  // Trailers (a MAC) are left unread, as by every LCM tool.
  void on_force(const lcm::ReceiveBuffer*, const std::string&, const tsmh::master_force_t* m) {
    if (m->num_joints != 2) return;
    for (double t : m->torque)
      if (!(std::fabs(t) <= peak_.load())) peak_ = std::fabs(t);  // NaN counts as a peak
    cell_.store(Force{m->enable != 0, {m->torque[0], m->torque[1]}});
    ++count_;
  }

  lcm::LCM lcm_;
  realtime::LatestValue<Force> cell_;
  std::atomic<double> peak_{0.0};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<bool> running_{true};
  std::thread thread_;
};

/// The console (unsigned MASTER_STATE, dead-man held) and the slave
/// (unsigned SLAVE_STATE, 0.1 N m of proximal torque), both at ~1 kHz.
class ConsoleAndSlave {
 public:
  explicit ConsoleAndSlave(std::string prefix) : prefix_(std::move(prefix)), lcm_(url()) {
    thread_ = std::thread([this] { run(); });
  }
  ~ConsoleAndSlave() { stop(); }
  void stop() {
    running_ = false;
    if (thread_.joinable()) thread_.join();
  }
  /// Sends raw bytes on the console's MASTER_STATE channel, between two
  /// regular messages.
  void inject(std::vector<std::uint8_t> bytes) {
    std::lock_guard lock(mutex_);
    injected_.push_back(std::move(bytes));
  }

 private:
  void run() {
    const std::string master = prefix_ + "MASTER_STATE", slave = prefix_ + "SLAVE_STATE";
    bridge::SlaveStateSample s = test::constant_tension_state(30.0, 20.0);
    std::int64_t seq = 0;
    auto next = Clock::now();
    while (running_) {
      const auto m = encode(master_state(seq), master, nullptr);
      lcm_.publish(master, m.data(), static_cast<unsigned>(m.size()));
      {
        std::lock_guard lock(mutex_);
        for (const auto& b : injected_)
          lcm_.publish(master, b.data(), static_cast<unsigned>(b.size()));
        injected_.clear();
      }
      s.utime = realtime::monotonic_utime();
      s.seq = seq++;
      bridge::publish_sample(lcm_, slave, s);
      next += 1ms;
      std::this_thread::sleep_until(next);
      if (Clock::now() > next + 50ms) next = Clock::now();
    }
  }

  std::string prefix_;
  lcm::LCM lcm_;
  std::mutex mutex_;
  std::vector<std::vector<std::uint8_t>> injected_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

class HostileDecode : public test::ScratchDirTest {
 protected:
  HostileDecode() : ScratchDirTest("tsmh-hostile-decode") {}

  // No link key anywhere the programs look (finding 1 ran the server
  // without one, on the default host-only URL).
  std::map<std::string, std::string> no_key_env() const {
    return {{"TSMH_LINK_KEY", ""}, {"HOME", dir_.string()}, {"XDG_CONFIG_HOME", dir_.string()}};
  }
  void skip_if_a_system_key_exists() {
    if (fs::exists("/etc/tsmh/link.key"))
      GTEST_SKIP() << "/etc/tsmh/link.key exists: the programs would run keyed";
  }

  /// The `lcm` device with `device_url` (empty: none, it follows the server's).
  fs::path write_config(const std::string& prefix, const std::string& device_url) {
    const fs::path p = dir_ / "server.yaml";
    std::ofstream(p)
        << "rate_hz: 1000\nfeedback: naive\n"
        << "device:\n  driver: lcm\n  settings: {"
        << (device_url.empty() ? "" : "url: '" + device_url + "', ") << "channel_prefix: " << prefix
        << ", dof: 2, stale_timeout_ms: 200, command_timeout_ms: 200}\n"
        << "lcm: {prefix: " << prefix << "}\n"
        << "realtime: {sched_fifo: false, lock_memory: false, cpu_dma_latency: false}\n"
        << "joints:\n"
        << "  - {params: paper, max_torque_nm: 0.3, max_rate_nm_per_s: 30}\n"
        << "  - {params: paper, max_torque_nm: 0.3, max_rate_nm_per_s: 30}\n";
    return p;
  }
  std::unique_ptr<Child> start_server(const fs::path& config, const std::string& lcm_url) {
    return std::make_unique<Child>(
        std::vector<std::string>{program(TSMH_HAPTIC_SERVER, "TSMH_SERVER_UNDER_TEST"), "--config",
                                 config.string(), "--lcm-url", lcm_url},
        dir_ / "server.log", no_key_env());
  }
};

bool rendering(const ForceListener& f) {
  const Force n = f.newest();
  return n.enable && std::fabs(n.torque[0]) > 0.05;
}

// The unsigned MASTER_STATE claiming 2^28 joints, into haptic-server running
// without a key on a host-only URL with the lcm driver: refused and counted,
// the session goes on, torque stays within max_torque_nm, and the server
// ends cleanly on SIGTERM with zero torque.
TEST_F(HostileDecode, ServerRefusesAMasterStateClaiming2pow28Joints) {
  skip_if_a_system_key_exists();
  const std::string prefix = unique_prefix();
  ForceListener force(prefix + "MASTER_FORCE");
  ConsoleAndSlave peer(prefix);
  auto server = start_server(write_config(prefix, url()), url());
  ASSERT_TRUE(wait_until([&] { return rendering(force); }, 8s)) << server->log();

  const std::string channel = prefix + "MASTER_STATE";
  peer.inject(claiming_2pow28_joints(master_state(1'000'000), channel, nullptr));
  std::this_thread::sleep_for(1500ms);  // the crash came 3.4 s later; the fault at once
  EXPECT_TRUE(server->running()) << server->log();
  EXPECT_TRUE(rendering(force)) << "the session must go on: the hostile message is dropped";
  EXPECT_LE(force.peak(), 0.3 + 1e-12) << "torque beyond max_torque_nm";

  server->signal(SIGTERM);
  std::string what;
  EXPECT_EQ(server->wait(5s, &what), 0) << what << "\n" << server->log();
  std::this_thread::sleep_for(100ms);
  const Force last = force.newest();
  EXPECT_FALSE(last.enable);
  EXPECT_EQ(last.torque[0], 0.0);
  EXPECT_EQ(last.torque[1], 0.0);
  EXPECT_LE(force.peak(), 0.3 + 1e-12);
  const std::string log = server->log();
  EXPECT_NE(log.find("device: 1 MASTER_STATE rejected, never used; the last: " + channel +
                     ": num_joints 268435456, expected 2"),
            std::string::npos)
      << log;
}

// --lcm-url moves the whole run: the lcm device has no url of its own and
// must listen where the server's link does (it listened on the default port
// beside a demo and faulted).
TEST_F(HostileDecode, ServerLcmUrlReachesTheLcmDevice) {
  skip_if_a_system_key_exists();
  const std::string prefix = unique_prefix();
  ForceListener force(prefix + "MASTER_FORCE");
  ConsoleAndSlave peer(prefix);
  auto server = start_server(write_config(prefix, ""), url());
  EXPECT_TRUE(wait_until([&] { return rendering(force); }, 8s))
      << "no MASTER_FORCE on --lcm-url's network\n"
      << server->log();
  server->signal(SIGTERM);
  EXPECT_EQ(server->wait(5s), 0) << server->log();
}

// A URL LCM reads as TTL 1 is not "host-confined": an error naming the
// option, before anything starts (it ran without a key).
TEST_F(HostileDecode, ServerRefusesARepeatedTtl) {
  skip_if_a_system_key_exists();
  const std::string prefix = unique_prefix();
  const std::string twice = "udpm://239.255.76.67:7761?ttl=0&ttl=1";
  auto server = start_server(write_config(prefix, ""), twice);
  std::string what;
  EXPECT_EQ(server->wait(10s, &what), 2) << what << "\n" << server->log();
  EXPECT_NE(server->log().find("LCM URL '" + twice + "': option 'ttl' is given twice"),
            std::string::npos)
      << server->log();
}

// The server's side of external-master-adapter: answers its MASTER_STATE
// with MASTER_FORCE (enable, 0.05 N m), and once with `hostile`.
// Plays the server: 1 kHz MASTER_FORCE, and once, at message 300, the
// hostile body (`hostile_body`: unsigned; signed here when keyed). Keyed, it
// first answers the adapter's session (as a server does), so the hostile
// message comes from the bound session and reaches the decoder: the body,
// not the session or the MAC, is what is wrong.
void serve_adapter(const std::string& prefix, bridge::MessageSigner* signer,
                   const std::vector<std::uint8_t>& hostile_body, Child& adapter,
                   std::chrono::milliseconds run_for) {
  lcm::LCM lcm(url());
  const std::string channel = prefix + "MASTER_FORCE";
  const test::SessionAnswer answer(url(), prefix + "MASTER_STATE",
                                   signer ? test::test_link_key() : nullptr, signer);
  tsmh::master_force_t f{};
  f.num_joints = 2;
  f.torque = {0.05, -0.05};
  f.enable = 1;
  const auto end = Clock::now() + run_for;
  bool sent = false;
  for (std::int64_t seq = 0; Clock::now() < end && adapter.running(); ++seq) {
    f.utime = realtime::monotonic_utime();
    f.seq = seq;
    const auto b = encode(f, channel, signer);
    lcm.publish(channel, b.data(), static_cast<unsigned>(b.size()));
    const bool bound =
        answer.session() == nullptr || answer.session()->state() == bridge::SessionState::kBound;
    if (!sent && seq >= 300 && bound) {
      std::vector<std::uint8_t> hostile = hostile_body;
      if (signer) {  // signed after the change: the MAC verifies, the body is hostile
        const std::size_t size = hostile.size();
        hostile.resize(size + bridge::kAuthTrailerBytes);
        signer->sign(channel, hostile.data(), size, hostile.data() + size);
      }
      lcm.publish(channel, hostile.data(), static_cast<unsigned>(hostile.size()));
      sent = true;
    }
    std::this_thread::sleep_for(1ms);
  }
  EXPECT_TRUE(sent) << "the adapter's session never bound";
}

void expect_adapter_survives(HostileDecode* t, const fs::path& dir, bool keyed) {
  const std::string prefix = unique_prefix();
  const std::string channel = prefix + "MASTER_FORCE";
  std::unique_ptr<bridge::MessageSigner> signer = keyed ? test::test_signer() : nullptr;
  if (keyed && !signer) GTEST_SKIP() << "TSMH_LINK_KEY is not set (ctest sets it)";
  tsmh::master_force_t hostile{};
  hostile.utime = realtime::monotonic_utime();
  hostile.seq = 1'000'000;
  hostile.num_joints = 2;
  hostile.torque = {0.2, 0.2};
  hostile.enable = 1;
  std::map<std::string, std::string> env = {{"HOME", dir.string()},
                                            {"XDG_CONFIG_HOME", dir.string()}};
  if (!keyed) env["TSMH_LINK_KEY"] = "";
  Child adapter({program(TSMH_EXTERNAL_MASTER_ADAPTER, "TSMH_ADAPTER_UNDER_TEST"), "--lcm-url",
                 url(), "--prefix", prefix, "--duration", "2.5"},
                dir / "adapter.log", env);
  serve_adapter(prefix, signer.get(), claiming_2pow28_joints(hostile, channel, nullptr), adapter,
                2s);
  std::string what;
  EXPECT_EQ(adapter.wait(8s, &what), 0) << what << "\n" << adapter.log();
  const std::string log = adapter.log();
  EXPECT_NE(log.find("rejected forces 1 (the last: num_joints 268435456, expected 2)"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("unauthenticated forces 0"), std::string::npos)
      << (keyed ? "signed with the right key: it is the body, not the MAC, that is wrong\n" : "")
      << log;
  (void)t;
}

TEST_F(HostileDecode, AdapterRefusesAMasterForceClaiming2pow28Joints) {
  skip_if_a_system_key_exists();
  expect_adapter_survives(this, dir_, /*keyed=*/false);
}

TEST_F(HostileDecode, AdapterRefusesItSignedWithTheRightKey) {
  expect_adapter_survives(this, dir_, /*keyed=*/true);
}

// tsm-devices --monitor lcm hung on it; now every reading line says why the
// message was refused, and it ends on time.
TEST_F(HostileDecode, MonitorReportsTheRejectionAndEnds) {
  skip_if_a_system_key_exists();
  const std::string prefix = unique_prefix();
  const std::string channel = prefix + "MASTER_STATE";
  Child monitor({program(TSMH_DEVICES, "TSMH_DEVICES_UNDER_TEST"), "--monitor", "lcm", "--lcm-url",
                 url(), "--prefix", prefix, "--seconds", "1.5"},
                dir_ / "monitor.log", no_key_env());
  lcm::LCM lcm(url());
  const auto hostile = claiming_2pow28_joints(master_state(7), channel, nullptr);
  for (int i = 0; i < 40 && monitor.running(); ++i) {
    lcm.publish(channel, hostile.data(), static_cast<unsigned>(hostile.size()));
    std::this_thread::sleep_for(50ms);
  }
  std::string what;
  EXPECT_EQ(monitor.wait(6s, &what), 0) << what << "\n" << monitor.log();
  EXPECT_NE(monitor.log().find(channel + ": num_joints 268435456, expected 2"), std::string::npos)
      << monitor.log();
}

}  // namespace
}  // namespace tsmh::haptics
