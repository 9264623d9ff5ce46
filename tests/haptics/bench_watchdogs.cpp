// How long torque and motion last after a program of a session dies, with the
// real programs over udpm on this host (docs/haptic-server.md, "Crash"). Each
// scenario runs --runs times; times are from kill() to the first sign on the
// bus (CLOCK_MONOTONIC), min / median / max:
//
//   kill-server-slave    SIGKILL haptic-server: virtual-slave holds after its
//                        command timeout (--command-timeout, default 0.1 s)
//   crash-server         SIGSEGV haptic-server: its crash handler's zero
//                        MASTER_FORCE, MASTER_COMMAND hold, and the slave holding
//   kill-server-adapter  SIGKILL haptic-server: external-master-adapter zeroes
//                        its torque after --watchdog-ms (default 50 ms)
//   kill-slave           SIGKILL virtual-slave: the server's stale fade brings
//                        MASTER_FORCE to 0 N m (stale_after_ms + fade_ms)
//
//   bench_watchdogs [--runs N] [--only NAME]   (run it in a network namespace
//   of its own, with TSMH_LINK_KEY set: the session is keyed)
#include <signal.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "realtime/quantile.hpp"
#include "server_bus.hpp"
#include "server_child.hpp"

namespace {

namespace fs = std::filesystem;
using tsmh::haptics::test::Bus;
using tsmh::haptics::test::Child;
using tsmh::haptics::test::Seen;
using tsmh::realtime::monotonic_now_ns;

const std::string kUrl = "udpm://239.255.76.67:7744?ttl=0&recv_buf_size=2097152";

template <class Pred>
bool wait_until(Pred done, double seconds) {
  const std::int64_t deadline = monotonic_now_ns() + static_cast<std::int64_t>(seconds * 1e9);
  while (!done()) {
    if (monotonic_now_ns() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  return true;
}

fs::path write_config(const fs::path& dir, const std::string& prefix) {
  const fs::path p = dir / "server.yaml";
  std::ofstream(p) << "rate_hz: 1000\nfeedback: naive\n"
                   << "device:\n  driver: lcm\n  settings: {url: '" << kUrl
                   << "', channel_prefix: " << prefix << ", dof: 2}\n"
                   << "lcm: {prefix: " << prefix << "}\n"
                   << "realtime: {sched_fifo: true, priority: 80, lock_memory: false, "
                      "cpu_dma_latency: false, cpu: -1}\n"
                   << "evaluation: {truth: false}\n"
                   << "joints:\n"
                   << "  - {params: paper, max_torque_nm: 0.3, max_rate_nm_per_s: 30}\n"
                   << "  - {params: paper, max_torque_nm: 0.3, max_rate_nm_per_s: 30}\n";
  return p;
}

bool rendering(const Seen& s) {
  return s.force_enable && std::max(std::fabs(s.torque[0]), std::fabs(s.torque[1])) > 0.005 &&
         s.command_enable && (s.slave_status & 1) != 0;
}

struct Series {
  explicit Series(std::string n) : name(std::move(n)) {}
  std::string name;
  std::vector<double> ms;
  void add(std::int64_t from_ns, std::int64_t to_ns) {
    if (to_ns > 0) ms.push_back(static_cast<double>(to_ns - from_ns) * 1e-6);
  }
  void print(int runs) const {
    if (ms.empty()) {
      std::printf("  %-44s never seen (%d runs)\n", name.c_str(), runs);
      return;
    }
    std::printf("  %-44s min %6.1f  median %6.1f  max %6.1f ms  (%zu of %d runs)\n", name.c_str(),
                *std::min_element(ms.begin(), ms.end()), tsmh::realtime::median(ms),
                *std::max_element(ms.begin(), ms.end()), ms.size(), runs);
  }
};

/// One session: slave, server, and either the Bus or the adapter as the console.
struct Session {
  Session(const fs::path& dir, const std::string& prefix, bool adapter)
      : bus(kUrl, prefix, !adapter),
        slave({TSMH_VIRTUAL_SLAVE, "--lcm-url", kUrl, "--prefix", prefix}, dir / "slave.log"),
        server({TSMH_HAPTIC_SERVER, "--config", write_config(dir, prefix).string(), "--lcm-url",
                kUrl, "--quiet"},
               dir / "server.log") {
    if (adapter)
      console = std::make_unique<Child>(
          std::vector<std::string>{TSMH_MASTER_ADAPTER, "--lcm-url", kUrl, "--prefix", prefix},
          dir / "adapter.log");
  }
  Bus bus;
  Child slave;
  Child server;
  std::unique_ptr<Child> console;
};

int run(const std::string& only, int runs) {
  const fs::path dir =
      fs::temp_directory_path() / ("tsmh-bench-watchdogs-" + std::to_string(getpid()));
  fs::create_directories(dir);
  int failures = 0;
  auto scenario = [&](const std::string& name, bool adapter, auto&& kill_and_measure) {
    if (!only.empty() && only != name) return false;
    std::printf("%s\n", name.c_str());
    for (int r = 0; r < runs; ++r) {
      std::string prefix = "W";  // += only: GCC 12's -Wrestrict misfires on "literal" + string
      prefix += std::to_string(getpid());
      prefix += "_";
      prefix += std::to_string(r);
      prefix += "_";
      Session s(dir, prefix, adapter);
      if (!wait_until([&] { return rendering(s.bus.seen()); }, 15.0)) {
        std::fprintf(stderr, "%s run %d: the session never rendered torque\n%s", name.c_str(), r,
                     s.server.log().c_str());
        ++failures;
        continue;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(300));
      kill_and_measure(s);
    }
    return true;
  };

  Series slave_hold("slave holding (virtual-slave command timeout)");
  if (scenario("kill-server-slave", false, [&](Session& s) {
        s.bus.mark();
        const std::int64_t t0 = monotonic_now_ns();
        s.server.signal(SIGKILL);
        wait_until([&] { return s.bus.seen().slave_holding_ns != 0; }, 3.0);
        slave_hold.add(t0, s.bus.seen().slave_holding_ns);
      }))
    slave_hold.print(runs);

  Series crash_force("MASTER_FORCE enable 0"), crash_command{"MASTER_COMMAND enable 0 (hold)"},
      crash_slave{"slave holding"};
  if (scenario("crash-server", false, [&](Session& s) {
        s.bus.mark();
        const std::int64_t t0 = monotonic_now_ns();
        s.server.signal(SIGSEGV);
        wait_until([&] { return s.bus.seen().slave_holding_ns != 0; }, 3.0);
        const Seen seen = s.bus.seen();
        crash_force.add(t0, seen.force_disabled_ns);
        crash_command.add(t0, seen.command_hold_ns);
        crash_slave.add(t0, seen.slave_holding_ns);
      })) {
    crash_force.print(runs);
    crash_command.print(runs);
    crash_slave.print(runs);
  }

  Series adapter_zero("adapter torque zeroed (--watchdog-ms)");
  if (scenario("kill-server-adapter", true, [&](Session& s) {
        const std::int64_t t0 = monotonic_now_ns();
        s.server.signal(SIGKILL);
        std::int64_t seen_ns = 0;
        wait_until(
            [&] {
              if (s.console->log().find("(watchdog): torque zeroed") == std::string::npos)
                return false;
              seen_ns = monotonic_now_ns();
              return true;
            },
            3.0);
        adapter_zero.add(t0, seen_ns);
      }))
    adapter_zero.print(runs);

  Series faded("MASTER_FORCE 0 N m (stale fade)");
  if (scenario("kill-slave", false, [&](Session& s) {
        s.bus.mark();
        const std::int64_t t0 = monotonic_now_ns();
        s.slave.signal(SIGKILL);
        wait_until([&] { return s.bus.seen().force_zero_ns != 0; }, 3.0);
        faded.add(t0, s.bus.seen().force_zero_ns);
      }))
    faded.print(runs);

  fs::remove_all(dir);
  return failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 5;
  std::string only;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) {
      runs = std::max(1, std::atoi(argv[++i]));
    } else if (a == "--only" && i + 1 < argc) {
      only = argv[++i];
    } else {
      std::fprintf(stderr, "usage: %s [--runs N] [--only NAME]\n", argv[0]);
      return 2;
    }
  }
  return run(only, runs);
}
