// A core-dumping signal sent to the real haptic-server while it renders
// torque (docs/haptic-server.md, "Crash"): the real virtual-slave and the
// server over real udpm on this host (ttl=0), keyed with the test key
// (TSMH_LINK_KEY, set by ctest). The test plays the master console through
// the server's `lcm` driver (signed MASTER_STATE in, MASTER_FORCE out) and
// listens to everything on the bus. One test per signal, each one asserting:
//   - the server dies of that signal (the exit status the kernel gives);
//   - the last MASTER_FORCE on the bus says enable 0 and 0 N m on every joint;
//   - the last MASTER_COMMAND on the bus says enable 0 (hold);
//   - the slave reports holding (SLAVE_STATE status bit 1) within 1 s,
//     although its own command timeout is 5 s: the hold, not its watchdog.
// Core dumps are off in the children (setrlimit).
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
#include <mutex>
#include <string>
#include <thread>
#include <tsmh/master_command_t.hpp>
#include <tsmh/master_force_t.hpp>
#include <tsmh/master_state_t.hpp>
#include <tsmh/slave_state_t.hpp>
#include <vector>

#include "bridge/crash_stop.hpp"
#include "bridge/link_auth.hpp"
#include "bridge/stop_signals.hpp"
#include "server_bus.hpp"
#include "server_child.hpp"
#include "wait_until.hpp"

namespace tsmh::haptics {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

// A port of its own: other tests' traffic never mixes in.
std::string url() {
  return "udpm://239.255.76.67:7743?ttl=0&recv_buf_size=2097152";
}

constexpr double kSlaveCommandTimeoutS = 5.0;

using test::wait_until;

class ServerCrash : public ::testing::TestWithParam<int> {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("tsmh-server-crash-" + std::to_string(getpid()) + "-" + std::to_string(GetParam()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write_config(const std::string& prefix) {
    const fs::path p = dir_ / "server.yaml";
    std::ofstream(p) << "rate_hz: 1000\nfeedback: naive\n"
                     << "device:\n  driver: lcm\n  settings: {url: '" << url()
                     << "', channel_prefix: " << prefix
                     << ", dof: 2, stale_timeout_ms: 200, command_timeout_ms: 200}\n"
                     << "lcm: {prefix: " << prefix << "}\n"
                     << "realtime: {sched_fifo: true, priority: 80, lock_memory: false, "
                        "cpu_dma_latency: false, cpu: -1}\n"
                     << "evaluation: {truth: false}\n"
                     << "joints:\n"
                     << "  - {params: paper, max_torque_nm: 0.3, max_rate_nm_per_s: 30}\n"
                     << "  - {params: paper, max_torque_nm: 0.3, max_rate_nm_per_s: 30}\n";
    return p;
  }

  fs::path dir_;
};

std::string server_binary() {
  // TSMH_SERVER_UNDER_TEST runs another build (e.g. before a fix) against these tests.
  const char* other = std::getenv("TSMH_SERVER_UNDER_TEST");
  return other ? other : TSMH_HAPTIC_SERVER;
}

bool rendering(const test::Seen& s) {
  return s.force_enable && std::max(std::fabs(s.torque[0]), std::fabs(s.torque[1])) > 0.005 &&
         s.command_enable && (s.slave_status & 1) != 0;
}

TEST_P(ServerCrash, ZeroTorqueAndSlaveHoldBeforeTheProcessEndsAsTheKernelEndsIt) {
  const int sig = GetParam();
  // Built with += only: GCC 12's -Wrestrict misfires on "literal" + std::string.
  std::string prefix = "C";
  prefix += std::to_string(getpid());
  prefix += "_";
  prefix += std::to_string(sig);
  prefix += "_";
  test::Bus bus(url(), prefix);
  test::Child slave(
      {TSMH_VIRTUAL_SLAVE, "--lcm-url", url(), "--prefix", prefix, "--command-timeout",
       std::to_string(kSlaveCommandTimeoutS), "--rt-priority", "0"},
      dir_ / "slave.log");
  test::Child server(
      {server_binary(), "--config", write_config(prefix).string(), "--lcm-url", url()},
      dir_ / "server.log");
  ASSERT_TRUE(wait_until([&] { return rendering(bus.seen()); }, 10s))
      << "the server never rendered torque with the slave following\n"
      << server.log() << slave.log();
  // Long enough for the crash messages to have been re-made several times.
  std::this_thread::sleep_for(500ms);
  ASSERT_TRUE(rendering(bus.seen())) << server.log();
  server.signal(sig);
  ASSERT_TRUE(server.wait_for_end(5s)) << "still running after " << bridge::signal_name(sig) << "\n"
                                       << server.log();
  ASSERT_TRUE(WIFSIGNALED(server.status())) << "exit code " << WEXITSTATUS(server.status()) << "\n"
                                            << server.log();
  EXPECT_EQ(WTERMSIG(server.status()), sig) << server.log();

  // The slave's own timeout is 5 s: holding within 1 s is the server's hold.
  EXPECT_TRUE(wait_until([&] { return (bus.seen().slave_status & 2) != 0; }, 1000ms))
      << "the slave still follows (status " << bus.seen().slave_status << ")\n"
      << slave.log();
  std::this_thread::sleep_for(100ms);  // anything still on its way arrives
  const test::Seen s = bus.seen();
  EXPECT_FALSE(s.force_enable) << "the last MASTER_FORCE still enables the console";
  EXPECT_EQ(s.torque[0], 0.0);
  EXPECT_EQ(s.torque[1], 0.0);
  EXPECT_FALSE(s.command_enable) << "the last MASTER_COMMAND still enables the slave";
  EXPECT_TRUE(slave.running()) << slave.log();
}

INSTANTIATE_TEST_SUITE_P(EveryCoreDumpingSignal, ServerCrash,
                         ::testing::ValuesIn(bridge::CrashStop::kSignals),
                         [](const ::testing::TestParamInfo<int>& p) {
                           return std::string(bridge::signal_name(p.param)).substr(3);
                         });

}  // namespace
}  // namespace tsmh::haptics
