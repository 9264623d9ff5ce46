// bench_bridge: what the bridge costs the 1 kHz loop, and how old data is
// when the loop sees it. Percentile printer (not run by ctest).
//   1. loop-side read of the newest SLAVE_STATE (Inbox::latest) while a real
//      udpm sender runs at 1 kHz                       target < 100 ns
//   2. publish cost seen by the calling thread: lcm publish directly vs
//      Outbox::publish (SPSC hand-off; publish thread woken by futex or polling)
//   3. one-way latency on loopback udpm (utime -> receive thread, every
//      message) and the age of what a 1 kHz loop reads, for the same three
//      ways of sending
//   0. what decoding one received message costs the receive thread: lcm-gen's
//      decode() alone vs the checked decoder (lcmtypes::MessageDecoder: type
//      hash, num_joints, exact size from the raw bytes first) and the bridge's
//      Decoder (the same, plus the copy into a sample); and refusing the
//      MASTER_STATE that claims 2^28 joints. Per message, from batches of 32
//      (a clock read costs about as much as one decode)
// Usage: bench_bridge [--count N] (messages per latency run, default 5000)
//        bench_bridge --decode-only   (section 0 only: no LCM needed)
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <lcm/lcm-cpp.hpp>
#include <string>
#include <thread>
#include <tsmh/master_state_t.hpp>
#include <vector>

#include "bridge/codec.hpp"
#include "bridge/receiver.hpp"
#include "bridge/sender.hpp"
#include "lcmtypes/message_decoder.hpp"
#include "realtime/clock.hpp"
#include "realtime/quantile.hpp"

namespace {

using namespace tsmh::bridge;

using tsmh::realtime::Percentiles;
using tsmh::realtime::percentiles;

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
  s.utime = tsmh::realtime::monotonic_utime();
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
  tsmh::realtime::sleep_until_ns(t);
}

// How the sending thread publishes.
struct Mode {
  const char* name;
  bool direct;                     // lcm publish in the sending thread
  std::chrono::microseconds poll;  // Outbox: publish-thread poll period (0: futex wake)
};
constexpr Mode kDirect{"direct lcm publish", true, std::chrono::microseconds(0)};
constexpr Mode kNotify{"Outbox, futex wake", false, std::chrono::microseconds(0)};
constexpr Mode kPoll100{"Outbox, 100 us poll", false, std::chrono::microseconds(100)};

// A 1 kHz sender thread.
class Pacer {
 public:
  Pacer(const BridgeConfig& cfg, int count, const Mode& mode)
      : tx_(cfg, SenderOptions{mode.poll}), direct_(mode.direct) {
    box_ = &tx_.outbox<SlaveStateSample>();
    tx_.start();
    channel_ = channel_name(cfg.prefix, Channel::kSlaveState);
    thread_ = std::thread([this, count] {
      std::int64_t next = tsmh::realtime::monotonic_now_ns();
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
  Pacer pacer(cfg, 4000, kNotify);
  SlaveStateSample s;
  while (inbox.latest(s) == 0)
    std::this_thread::sleep_for(std::chrono::milliseconds(1));

  // Batches of 1000 back-to-back reads: per-read mean of each batch.
  constexpr int kBatch = 1000;
  std::vector<double> batch_ns;
  volatile std::int64_t sink = 0;
  for (int b = 0; b < 2000; ++b) {
    const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
    for (int i = 0; i < kBatch; ++i) {
      inbox.latest(s);
      sink = sink + s.seq;
    }
    batch_ns.push_back(static_cast<double>(tsmh::realtime::monotonic_now_ns() - t0) / kBatch);
  }
  // Single reads timed one by one, as the loop does once per tick (includes
  // ~20 ns of clock_gettime; the timer alone is measured for comparison).
  std::vector<double> single_ns, timer_ns;
  for (int i = 0; i < 200'000; ++i) {
    const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
    inbox.latest(s);
    const std::int64_t t1 = tsmh::realtime::monotonic_now_ns();
    single_ns.push_back(static_cast<double>(t1 - t0));
    const std::int64_t t2 = tsmh::realtime::monotonic_now_ns();
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
  // One channel per way of sending, each with a subscriber, as in operation
  // (the kernel copies every datagram to the local subscribers in sendmsg).
  const BridgeConfig direct_cfg{std::string(kDefaultLcmUrl), prefix + "PUBD_"};
  const BridgeConfig notify_cfg{std::string(kDefaultLcmUrl), prefix + "PUBN_"};
  const BridgeConfig poll_cfg{std::string(kDefaultLcmUrl), prefix + "PUBP_"};
  Receiver rx_direct(direct_cfg), rx_notify(notify_cfg), rx_poll(poll_cfg);
  auto& in_direct = rx_direct.subscribe<SlaveStateSample>();
  auto& in_notify = rx_notify.subscribe<SlaveStateSample>();
  auto& in_poll = rx_poll.subscribe<SlaveStateSample>();
  rx_direct.start();
  rx_notify.start();
  rx_poll.start();
  Sender notify_tx(notify_cfg);
  auto& notify_box = notify_tx.outbox<SlaveStateSample>();
  notify_tx.start();
  Sender poll_tx(poll_cfg, SenderOptions{std::chrono::microseconds(100)});
  auto& poll_box = poll_tx.outbox<SlaveStateSample>();
  poll_tx.start();
  const std::string channel = channel_name(direct_cfg.prefix, Channel::kSlaveState);

  // Interleaved at 1 kHz each so that all three see the same machine load.
  std::vector<double> direct_us, notify_us, poll_us;
  std::int64_t next = tsmh::realtime::monotonic_now_ns();
  int seq = 0;
  auto timed = [&](std::vector<double>& out, auto&& publish) {
    const SlaveStateSample s = sample(seq / 3);
    ++seq;
    const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
    publish(s);
    out.push_back(static_cast<double>(tsmh::realtime::monotonic_now_ns() - t0) * 1e-3);
    next += 333'333;
    sleep_until_ns(next);
  };
  for (int i = 0; i < count; ++i) {
    timed(direct_us,
          [&](const SlaveStateSample& s) { publish_sample(notify_tx.lcm(), channel, s); });
    timed(notify_us, [&](const SlaveStateSample& s) { notify_box.publish(s); });
    timed(poll_us, [&](const SlaveStateSample& s) { poll_box.publish(s); });
  }
  print_header("2. publish cost in the calling thread, SLAVE_STATE 2 joints, 1 kHz each");
  print_row("lcm publish directly (encode + sendmsg)", "us", direct_us);
  print_row("Outbox::publish, futex wake", "us", notify_us);
  print_row("Outbox::publish, 100 us polling thread", "us", poll_us);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  std::printf("  outboxes dropped %llu + %llu (ring full); accepted %llu / %llu / %llu of %d\n",
              static_cast<unsigned long long>(notify_box.stats().dropped_full),
              static_cast<unsigned long long>(poll_box.stats().dropped_full),
              static_cast<unsigned long long>(in_direct.stats().accepted),
              static_cast<unsigned long long>(in_notify.stats().accepted),
              static_cast<unsigned long long>(in_poll.stats().accepted), count);
}

void bench_latency(const std::string& prefix, int count, const Mode& mode, const char* tag) {
  const BridgeConfig cfg{std::string(kDefaultLcmUrl), prefix + tag};
  Receiver rx(cfg);
  auto& inbox = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  rx.start();
  std::vector<double> age_us, fresh_us;
  {
    Pacer pacer(cfg, count, mode);
    // A 1 kHz "loop" (absolute deadlines, half a period after the sender's
    // ticks) reads the newest sample every tick, as the haptic loop does: with
    // no delay the age it sees would be 500 us.
    SlaveStateSample s;
    std::uint64_t last_version = 0;
    std::int64_t next = tsmh::realtime::monotonic_now_ns() + 500'000;
    for (int tick = 0; tick < count + 200; ++tick) {
      next += 1'000'000;
      sleep_until_ns(next);
      const std::uint64_t v = inbox.latest(s);
      if (v == 0) continue;
      const double age =
          static_cast<double>(tsmh::realtime::monotonic_now_ns() - s.utime * 1000) * 1e-3;
      if (tick < count) age_us.push_back(age);
      if (v != last_version) fresh_us.push_back(age);
      last_version = v;
      if (s.seq == count - 1) break;
    }
  }
  const ChannelStats st = inbox.stats();
  std::string title = "3. latency on udpm loopback, sender at 1 kHz: ";
  title += mode.name;
  print_header(title.c_str());
  std::printf(
      "  %-44s %7.3g %7.3g %7s %7.3g %8s %7.3g  us (n=%llu, min %.3g; p50/p99 to 12.5 %%)\n",
      "one-way, every message (Inbox histogram)", st.latency.mean_us, st.latency.p50_us, "",
      st.latency.p99_us, "", st.latency.max_us, static_cast<unsigned long long>(st.latency.count),
      st.latency.min_us);
  print_row("age of the sample a 1 kHz loop reads (+500 phase)", "us", age_us);
  print_row("age when the loop first sees a new sample", "us", fresh_us);
  std::printf("  accepted %llu of %d, gaps %llu, dropped %llu\n",
              static_cast<unsigned long long>(st.accepted), count,
              static_cast<unsigned long long>(st.seq_gaps),
              static_cast<unsigned long long>(st.dropped()));
}

// ns per call of `f`, one value per batch of 32 calls, `batches` values.
template <class F>
std::vector<double> per_call_ns(int batches, F&& f) {
  constexpr int kBatch = 32;
  std::vector<double> ns;
  ns.reserve(static_cast<std::size_t>(batches));
  for (int i = 0; i < 1000; ++i)
    f();  // warm the caches and the branch predictors
  for (int b = 0; b < batches; ++b) {
    const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
    for (int i = 0; i < kBatch; ++i)
      f();
    ns.push_back(static_cast<double>(tsmh::realtime::monotonic_now_ns() - t0) / kBatch);
  }
  return ns;
}

void bench_decode() {
  print_header("0. decoding one received message, ns per message (batches of 32)");
  constexpr int kBatches = 20000;
  std::vector<std::uint8_t> state_bytes;
  encode_sample(sample(1), state_bytes);
  volatile int sink = 0;

  tsmh::slave_state_t plain;  // lcm-gen alone, reusing its vectors
  print_row("SLAVE_STATE 2j: lcm-gen decode() alone", "ns", per_call_ns(kBatches, [&] {
              sink =
                  sink + plain.decode(state_bytes.data(), 0, static_cast<int>(state_bytes.size()));
            }));
  tsmh::lcmtypes::MessageDecoder<tsmh::slave_state_t> checked({1, kMaxJoints});
  print_row("SLAVE_STATE 2j: MessageDecoder (checked)", "ns", per_call_ns(kBatches, [&] {
              sink = sink + static_cast<int>(
                                checked.decode(state_bytes.data(), state_bytes.size()).has_value());
            }));
  Decoder<SlaveStateSample> bridge_decoder;
  SlaveStateSample out;
  print_row(
      "SLAVE_STATE 2j: bridge Decoder (+ sample)", "ns", per_call_ns(kBatches, [&] {
        sink = sink +
               static_cast<int>(
                   bridge_decoder.decode(state_bytes.data(), state_bytes.size(), out).has_value());
      }));

  tsmh::master_state_t m{};
  m.num_joints = 2;
  m.q.assign(2, 0.1);
  m.qd.assign(2, 0.2);
  std::vector<std::uint8_t> master_bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(master_bytes.data(), 0, static_cast<int>(master_bytes.size()));
  tsmh::master_state_t master_plain;
  print_row("MASTER_STATE 2j: lcm-gen decode() alone", "ns", per_call_ns(kBatches, [&] {
              sink = sink + master_plain.decode(master_bytes.data(), 0,
                                                static_cast<int>(master_bytes.size()));
            }));
  tsmh::lcmtypes::MessageDecoder<tsmh::master_state_t> master_checked({2, 2});
  print_row("MASTER_STATE 2j: MessageDecoder (checked)", "ns", per_call_ns(kBatches, [&] {
              sink =
                  sink +
                  static_cast<int>(
                      master_checked.decode(master_bytes.data(), master_bytes.size()).has_value());
            }));
  auto hostile = master_bytes;
  hostile[24] = 0x10;  // num_joints 2^28, body of 2 joints
  hostile[27] = 0x00;
  print_row("MASTER_STATE claiming 2^28 joints: refused", "ns", per_call_ns(kBatches, [&] {
              sink = sink + static_cast<int>(
                                master_checked.decode(hostile.data(), hostile.size()).has_value());
            }));
}

}  // namespace

int main(int argc, char** argv) {
  int count = 5000;
  for (int i = 1; i + 1 < argc; ++i)
    if (std::string(argv[i]) == "--count") count = std::max(100, std::atoi(argv[i + 1]));
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]) == "--decode-only") {
      bench_decode();
      return 0;
    }
  const std::string prefix = "BENCH" + std::to_string(getpid()) + "_";
  std::printf("bench_bridge: LCM udpm %s, %d messages per run, utime resolution 1 us\n",
              std::string(kDefaultLcmUrl).c_str(), count);
  try {
    bench_decode();
    bench_read(prefix);
    bench_publish_cost(prefix, count);
    bench_latency(prefix, count, kNotify, "LATN_");
    bench_latency(prefix, count, kPoll100, "LATP_");
    bench_latency(prefix, count, kDirect, "LATD_");
  } catch (const BridgeError& e) {
    std::fprintf(stderr, "bench_bridge: %s\n", e.what());
    return 1;
  }
  return 0;
}
