// bench_bridge: what the bridge costs the 1 kHz loop, and how old data is
// when the loop sees it. Percentile printer (not run by ctest).
//   1. loop-side read of the newest SLAVE_STATE (Inbox::latest) while a real
//      udpm sender runs at 1 kHz                       target < 100 ns
//   2. publish cost seen by the calling thread: lcm publish directly vs
//      Outbox::publish (SPSC hand-off to the publish thread)
//   3. one-way latency on loopback udpm (utime -> receive thread, and
//      utime -> the loop's first read), through Outbox and directly
// Usage: bench_bridge [--count N] (messages per latency run, default 5000)
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <vector>

#include "bridge/clock.hpp"
#include "bridge/receiver.hpp"
#include "bridge/sender.hpp"

namespace {

using namespace tsmh::bridge;

struct Percentiles {
  double p50, p90, p99, p999, max, mean;
};

Percentiles percentiles(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  auto at = [&](double p) {
    return v[static_cast<std::size_t>(p * static_cast<double>(v.size() - 1))];
  };
  double sum = 0;
  for (double x : v)
    sum += x;
  return {at(0.5), at(0.9), at(0.99), at(0.999), v.back(), sum / static_cast<double>(v.size())};
}

void print_row(const char* name, const char* unit, const std::vector<double>& v) {
  const Percentiles p = percentiles(v);
  std::printf("  %-44s %7.3g %7.3g %7.3g %7.3g %8.3g %7.3g  %s (n=%zu)\n", name, p.mean, p.p50,
              p.p90, p.p99, p.p999, p.max, unit, v.size());
}

void print_header(const char* title) {
  std::printf("\n%s\n  %-44s %7s %7s %7s %7s %8s %7s\n", title, "", "mean", "p50", "p90", "p99",
              "p99.9", "max");
}

SlaveStateSample sample(std::int64_t seq) {
  SlaveStateSample s;
  s.utime = monotonic_utime();
  s.seq = seq;
  s.num_joints = 2;
  for (std::size_t j = 0; j < 2; ++j) {
    s.x_in[j] = 0.001 * static_cast<double>(seq);
    s.x_out[j] = s.x_in[j];
    s.T1[j] = 10;
    s.T3[j] = 5;
    s.radius_m[j] = 0.01;
  }
  return s;
}

void sleep_until_ns(std::int64_t t) {
  const timespec ts{static_cast<time_t>(t / 1'000'000'000), static_cast<long>(t % 1'000'000'000)};
  clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
}

// A 1 kHz sender thread; `direct`: lcm publish in the thread, else through an Outbox.
class Pacer {
 public:
  Pacer(const BridgeConfig& cfg, int count, bool direct) : tx_(cfg), direct_(direct) {
    box_ = &tx_.outbox<SlaveStateSample>();
    tx_.start();
    channel_ = channel_name(cfg.prefix, Channel::SlaveState);
    thread_ = std::thread([this, count] {
      std::int64_t next = monotonic_now_ns();
      for (int i = 0; i < count && !stop_; ++i) {
        const SlaveStateSample s = sample(i);
        if (direct_)
          publish_sample(tx_.lcm(), channel_, s);
        else
          box_->publish(s);
        next += 1'000'000;
        sleep_until_ns(next);
      }
    });
  }
  ~Pacer() {
    stop_ = true;
    thread_.join();
  }
  void join() { thread_.join(); }

 private:
  Sender tx_;
  bool direct_;
  Outbox<SlaveStateSample>* box_;
  std::string channel_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

void bench_read(const std::string& prefix) {
  const BridgeConfig cfg{std::string(kDefaultLcmUrl), prefix + "READ_"};
  Receiver rx(cfg);
  auto& inbox = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  rx.start();
  Pacer pacer(cfg, 4000, /*direct=*/false);
  SlaveStateSample s;
  while (inbox.latest(s) == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));

  // Batches of 1000 back-to-back reads: per-read mean of each batch.
  constexpr int kBatch = 1000;
  std::vector<double> batch_ns;
  volatile std::int64_t sink = 0;
  for (int b = 0; b < 2000; ++b) {
    const std::int64_t t0 = monotonic_now_ns();
    for (int i = 0; i < kBatch; ++i) {
      inbox.latest(s);
      sink = sink + s.seq;
    }
    batch_ns.push_back(static_cast<double>(monotonic_now_ns() - t0) / kBatch);
  }
  // Single reads timed one by one, as the loop does once per tick (includes
  // ~20 ns of clock_gettime; the timer alone is measured for comparison).
  std::vector<double> single_ns, timer_ns;
  for (int i = 0; i < 200'000; ++i) {
    const std::int64_t t0 = monotonic_now_ns();
    inbox.latest(s);
    const std::int64_t t1 = monotonic_now_ns();
    single_ns.push_back(static_cast<double>(t1 - t0));
    const std::int64_t t2 = monotonic_now_ns();
    timer_ns.push_back(static_cast<double>(t2 - t1));
  }
  print_header(
      "1. loop-side read of the newest SLAVE_STATE (Inbox::latest, 2 joints), udpm sender at 1 "
      "kHz");
  std::printf("  sample size %zu bytes\n", sizeof(SlaveStateSample));
  print_row("latest(): mean of 1000 back-to-back reads", "ns", batch_ns);
  print_row("latest(): one read, timed (incl. timer)", "ns", single_ns);
  print_row("timer alone (clock_gettime pair)", "ns", timer_ns);
}

void bench_publish_cost(const std::string& prefix, int count) {
  const BridgeConfig cfg{std::string(kDefaultLcmUrl), prefix + "PUB_"};
  // A subscriber exists, as in operation (the kernel loops packets back to it).
  Receiver rx(cfg);
  auto& inbox = rx.subscribe<SlaveStateSample>();
  rx.start();
  Sender tx(cfg);
  auto& box = tx.outbox<SlaveStateSample>();
  tx.start();
  const std::string channel = channel_name(cfg.prefix, Channel::SlaveState);

  std::vector<double> direct_us, outbox_us;
  std::int64_t next = monotonic_now_ns();
  for (int i = 0; i < count; ++i) {
    SlaveStateSample s = sample(2 * i);
    std::int64_t t0 = monotonic_now_ns();
    publish_sample(tx.lcm(), channel, s);
    direct_us.push_back(static_cast<double>(monotonic_now_ns() - t0) * 1e-3);
    next += 500'000;
    sleep_until_ns(next);
    s = sample(2 * i + 1);
    t0 = monotonic_now_ns();
    box.publish(s);
    outbox_us.push_back(static_cast<double>(monotonic_now_ns() - t0) * 1e-3);
    next += 500'000;
    sleep_until_ns(next);
  }
  print_header("2. publish cost in the calling thread, SLAVE_STATE 2 joints, 1 kHz");
  print_row("lcm publish directly (encode + sendmsg)", "us", direct_us);
  print_row("Outbox::publish (ring copy + futex wake)", "us", outbox_us);
  std::printf("  outbox: %llu dropped (ring full); receiver accepted %llu of %d\n",
              static_cast<unsigned long long>(box.stats().dropped_full),
              static_cast<unsigned long long>(inbox.stats().accepted), 2 * count);
}

void bench_latency(const std::string& prefix, int count, bool direct) {
  const BridgeConfig cfg{std::string(kDefaultLcmUrl), prefix + (direct ? "LATD_" : "LATO_")};
  Receiver rx(cfg);
  auto& inbox = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  rx.start();
  std::vector<double> to_receive_us, to_loop_us;
  {
    Pacer pacer(cfg, count, direct);
    // The "loop" spins on latest() and notes when each new version shows up.
    std::uint64_t last_version = 0;
    SlaveStateSample s;
    const std::int64_t give_up = monotonic_now_ns() + (count + 2000) * 1'000'000LL;
    while (static_cast<int>(to_loop_us.size()) < count && monotonic_now_ns() < give_up) {
      const std::uint64_t v = inbox.latest(s);
      if (v == last_version) continue;
      const std::int64_t now = monotonic_now_ns();
      last_version = v;
      to_receive_us.push_back(static_cast<double>(s.receive_ns - s.utime * 1000) * 1e-3);
      to_loop_us.push_back(static_cast<double>(now - s.utime * 1000) * 1e-3);
      if (s.seq == count - 1) break;
    }
  }
  const ChannelStats st = inbox.stats();
  print_header(direct ? "3b. one-way latency, udpm loopback, sender publishes directly, 1 kHz"
                      : "3a. one-way latency, udpm loopback, sender uses an Outbox, 1 kHz");
  print_row("utime -> receive thread (receive_ns)", "us", to_receive_us);
  print_row("utime -> loop sees it (busy-polling latest)", "us", to_loop_us);
  std::printf("  accepted %llu, gaps %llu, dropped %llu; Inbox histogram p50 %.0f us p99 %.0f us\n",
              static_cast<unsigned long long>(st.accepted),
              static_cast<unsigned long long>(st.seq_gaps),
              static_cast<unsigned long long>(st.dropped()), st.latency.p50_us, st.latency.p99_us);
}

}  // namespace

int main(int argc, char** argv) {
  int count = 5000;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--count") count = std::max(100, std::atoi(argv[i + 1]));
  const std::string prefix = "BENCH" + std::to_string(getpid()) + "_";
  std::printf("bench_bridge: LCM udpm %s, %d messages per run, utime resolution 1 us\n",
              std::string(kDefaultLcmUrl).c_str(), count);
  try {
    bench_read(prefix);
    bench_publish_cost(prefix, count);
    bench_latency(prefix, count, /*direct=*/false);
    bench_latency(prefix, count, /*direct=*/true);
  } catch (const BridgeError& e) {
    std::fprintf(stderr, "bench_bridge: %s\n", e.what());
    return 1;
  }
  return 0;
}
