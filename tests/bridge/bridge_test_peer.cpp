// A second process for the bridge tests.
//   bridge_test_peer open URL
//       opens LCM at URL; prints "opened" or the BridgeError text; exit 0 / 3.
//   bridge_test_peer publish URL PREFIX COUNT RATE_HZ [truth]
//       publishes COUNT SLAVE_STATE (and SLAVE_TRUTH with the same seq) through
//       a Sender's Outboxes at RATE_HZ with absolute deadlines, then exits
//       after the publish thread has sent everything.
//   bridge_test_peer publish-direct URL PREFIX COUNT RATE_HZ [truth]
//       the same with synchronous publishes and, after a stall, a re-based
//       schedule: no bursts (lcm-logger's 30-message queue drops bursts).
//   bridge_test_peer crash URL CHANNEL SIGNAL
//       a thread publishes "alive" on CHANNEL through LCM every 200 us; a
//       CrashStop holds the datagram "crashed" for CHANNEL; after 50 ms the
//       process sends itself SIGNAL (core dumps off) and must die of it with
//       "crashed" the last message on CHANNEL.
//   bridge_test_peer crash-node NODE SIGNAL
//       the same for a device node (a FIFO standing in for hidraw): a thread
//       writes "torque!!" to it every 200 us through its own descriptor; the
//       CrashStop writes "zeroed!!" through a second one.
#include <fcntl.h>
#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>
#include <thread>

#include "bridge/codec.hpp"
#include "bridge/crash_stop.hpp"
#include "bridge/lcm_url.hpp"
#include "bridge/sender.hpp"
#include "realtime/clock.hpp"
#include "test_samples.hpp"

namespace {

int open_mode(const std::string& url) {
  try {
    auto lcm = tsmh::bridge::open_lcm(url);
    std::printf("opened\n");
    return 0;
  } catch (const tsmh::bridge::BridgeError& e) {
    std::printf("%s\n", e.what());
    return 3;
  }
}

std::int64_t next_tick(std::int64_t next_ns, std::int64_t period_ns, bool rebase_when_late) {
  next_ns += period_ns;
  if (rebase_when_late) next_ns = std::max(next_ns, tsmh::realtime::monotonic_now_ns());
  return next_ns;
}

int publish_mode(const std::string& url, const std::string& prefix, long count, double rate_hz,
                 bool truth, bool direct) {
  using namespace tsmh::bridge;
  Sender tx({.url = url, .prefix = prefix});
  auto& states = tx.outbox<SlaveStateSample>();
  auto& truths = tx.outbox<SlaveTruthSample>();
  tx.start();
  const std::string state_channel = channel_name(prefix, Channel::kSlaveState);
  const std::string truth_channel = channel_name(prefix, Channel::kSlaveTruth);
  const auto period_ns = static_cast<std::int64_t>(1e9 / rate_hz);
  std::int64_t next = tsmh::realtime::monotonic_now_ns();
  long errors = 0;
  for (long i = 0; i < count; ++i) {
    const std::int64_t utime = tsmh::realtime::monotonic_utime();
    if (direct) {
      errors += publish_sample(tx.lcm(), state_channel, test::make_state(i, utime)) != 0;
      if (truth) errors += publish_sample(tx.lcm(), truth_channel, test::make_truth(i, utime)) != 0;
    } else {
      // Not a real-time loop: wait for ring space rather than drop, so the
      // tests can count on every message being sent even on a stalled machine.
      while (!states.publish(test::make_state(i, utime)))
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      while (truth && !truths.publish(test::make_truth(i, utime)))
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    next = next_tick(next, period_ns, direct);
    tsmh::realtime::sleep_until_ns(next);
  }
  tx.stop();
  const auto s = states.stats();
  const long published = direct ? count : static_cast<long>(s.published);
  errors += static_cast<long>(s.publish_errors);
  std::printf("published %ld errors %ld\n", published, errors);
  return published == count && errors == 0 ? 0 : 1;
}

int crash_mode(const std::string& url, const std::string& channel, int sig) {
  const rlimit no_core{0, 0};
  setrlimit(RLIMIT_CORE, &no_core);
  const auto endpoint = tsmh::bridge::udpm_endpoint(url);
  if (!endpoint) return 2;
  auto lcm = tsmh::bridge::open_lcm(url);
  std::atomic<bool> stop{false};
  std::thread alive([&] {
    static constexpr char kAlive[] = "alive";
    while (!stop.load()) {
      lcm->publish(channel, kAlive, sizeof kAlive - 1);
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  tsmh::bridge::CrashStop crash;
  const std::size_t out = crash.add_datagram(*endpoint);
  static constexpr std::uint8_t kCrashed[] = {'c', 'r', 'a', 's', 'h', 'e', 'd'};
  std::uint8_t datagram[128];
  const std::size_t n = tsmh::bridge::frame_udpm_short(channel, 7, kCrashed, sizeof kCrashed,
                                                       datagram, sizeof datagram);
  if (n == 0 || !crash.set(out, datagram, n)) return 2;
  crash.find_senders({ntohs(endpoint->group.sin_port)});
  crash.install();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  kill(getpid(), sig);
  std::this_thread::sleep_for(std::chrono::seconds(2));
  stop = true;
  alive.join();
  return 0;  // the signal did not end the process: the test fails on this
}

int crash_node_mode(const std::string& node, int sig) {
  const rlimit no_core{0, 0};
  setrlimit(RLIMIT_CORE, &no_core);
  const int busy = open(node.c_str(), O_WRONLY | O_CLOEXEC);  // the driver's own descriptor
  if (busy < 0) return 2;
  std::atomic<bool> stop{false};
  std::thread torque([&] {
    static constexpr char kTorque[] = "torque!!";
    while (!stop.load()) {
      if (write(busy, kTorque, 8) != 8) break;
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  tsmh::bridge::CrashStop crash;
  const std::size_t out = crash.add_node(node);
  static constexpr std::uint8_t kZeroed[] = {'z', 'e', 'r', 'o', 'e', 'd', '!', '!'};
  if (!crash.set(out, kZeroed, sizeof kZeroed)) return 2;
  crash.find_senders({}, {node});
  crash.install();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  kill(getpid(), sig);
  std::this_thread::sleep_for(std::chrono::seconds(2));
  stop = true;
  torque.join();
  return 0;  // the signal did not end the process: the test fails on this
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "open" && argc == 3) return open_mode(argv[2]);
  if ((mode == "publish" || mode == "publish-direct") && (argc == 6 || argc == 7))
    return publish_mode(argv[2], argv[3], std::atol(argv[4]), std::atof(argv[5]),
                        argc == 7 && std::string(argv[6]) == "truth", mode == "publish-direct");
  if (mode == "crash" && argc == 5) return crash_mode(argv[2], argv[3], std::atoi(argv[4]));
  if (mode == "crash-node" && argc == 4) return crash_node_mode(argv[2], std::atoi(argv[3]));
  std::fprintf(stderr,
               "usage: %s open URL | publish[-direct] URL PREFIX COUNT RATE_HZ [truth] | crash URL "
               "CHANNEL SIGNAL | crash-node NODE SIGNAL\n",
               argv[0]);
  return 2;
}
