// bench_master_devices: numbers for the master device layer (not a test).
//   codec and lock-free cell costs; a 1 kHz loop against the real-time
//   emulator through the console driver (reading age, call costs, lateness);
//   unplug detection and replug recovery times; sim device speed in
//   simulated time.
// Usage: bench_master_devices [seconds-of-1kHz-run, default 5]

#include <time.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <thread>
#include <vector>

#include "master_devices/builtin_drivers.hpp"
#include "master_devices/console_device.hpp"
#include "master_devices/emulator_bus.hpp"
#include "master_devices/protocol.hpp"
#include "master_devices/sim_device.hpp"
#include "realtime/clock.hpp"
#include "realtime/latest_value.hpp"
#include "realtime/quantile.hpp"

namespace md = tsmh::master_devices;
namespace p = tsmh::master_devices::protocol;

namespace {

using tsmh::realtime::Percentiles;
using tsmh::realtime::percentiles;

void print(const char* what, const char* unit, const Percentiles& p) {
  std::printf("  %-34s p50 %8.2f  p99 %8.2f  p99.9 %8.2f  max %8.2f %s\n", what, p.p50, p.p99,
              p.p999, p.max, unit);
}

template <class F>
double ns_per_op(int n, F&& f) {
  const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
  for (int i = 0; i < n; ++i)
    f(i);
  return static_cast<double>(tsmh::realtime::monotonic_now_ns() - t0) / n;
}

void sleep_until(std::int64_t t_ns) {
  tsmh::realtime::sleep_until_ns(t_ns);
}

}  // namespace

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 5.0;

  std::printf("== codec (single thread)\n");
  {
    std::array<std::uint8_t, p::kMaxReportSize> buf{};
    p::InputReport in;
    in.counts = {123456, -654321};
    volatile std::size_t sink = 0;
    const double enc = ns_per_op(1'000'000, [&](int i) {
      in.sequence = static_cast<std::uint16_t>(i);
      sink = sink + p::encode(in, buf).value;
    });
    const std::span<const std::uint8_t> bytes(buf.data(), p::kInputReportSize);
    const double dec =
        ns_per_op(1'000'000, [&](int) { sink = sink + p::decode_input(bytes).value.sequence; });
    std::printf("  encode input report %.1f ns, decode input report %.1f ns\n", enc, dec);
  }

  std::printf("== LatestValue<DeviceReading> (single thread)\n");
  {
    tsmh::realtime::LatestValue<md::DeviceReading> cell;
    tsmh::realtime::LatestValueReader<md::DeviceReading> reader(cell);
    md::DeviceReading r;
    const double both = ns_per_op(1'000'000, [&](int i) {
      r.sequence = static_cast<std::uint64_t>(i);
      cell.store(r);
      reader.fetch(r);
    });
    std::printf("  store + fetch %.1f ns (sizeof reading %zu bytes)\n", both,
                sizeof(md::DeviceReading));
  }

  std::printf("== 1 kHz loop vs real-time emulator through the console driver, %.1f s\n", seconds);
  {
    md::EmulatorBus::Options o;
    o.pacing = md::EmulatorBus::Pacing::kRealTime;
    o.firmware = md::firmware_for_profile(md::builtin_console_profile());
    // Command-to-motor latency: the loop writes a torque that encodes its
    // tick (k % 1000 + 1) x 0.2 mN m; the firmware side decodes the torque it
    // applies and looks up when that tick wrote it.
    auto written_ns = std::make_shared<std::array<std::atomic<std::int64_t>, 1000>>();
    auto latency_us = std::make_shared<std::vector<double>>();
    latency_us->reserve(100000);
    auto last_index = std::make_shared<int>(-1);
    o.after_output = [written_ns, latency_us, last_index](const md::Firmware& fw) {
      const double tau = fw.applied_torque_nm(1);
      const int index = static_cast<int>(std::lround(tau / 2e-4)) - 1;
      if (index < 0 || index >= 1000 || index == *last_index) return;
      *last_index = index;
      const std::int64_t t = (*written_ns)[static_cast<std::size_t>(index)].load();
      if (t > 0) latency_us->push_back((tsmh::realtime::monotonic_now_ns() - t) * 1e-3);
    };
    auto bus = std::make_shared<md::EmulatorBus>(o);
    md::ConsoleSettings cs;
    cs.reconnect_interval_ms = 20;
    cs.command_timeout_ms = 100;
    md::ConsoleDevice dev("emulator", md::builtin_console_profile(), cs, bus);
    dev.open();
    dev.set_enabled(true);
    std::vector<double> age_us, read_ns, write_ns, late_us;
    // Age of the newest sample (dated on the device clock) at every tick
    // while the device streams: how often a freshness bound of N periods
    // would call a streaming device stale.
    std::vector<double> streaming_age_us;
    int stale_ticks = 0;
    const int ticks = static_cast<int>(seconds * 1000);
    int fresh = 0;
    int unplug_at = ticks / 2;
    int detected_after = -1;
    int recovered_after = -1;
    std::int64_t next = tsmh::realtime::monotonic_now_ns();
    for (int k = 0; k < ticks; ++k) {
      next += 1'000'000;
      sleep_until(next);
      const std::int64_t now = tsmh::realtime::monotonic_now_ns();
      late_us.push_back((now - next) * 1e-3);
      if (k == unplug_at) bus->unplug();
      if (k == unplug_at + 100) bus->replug();
      const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
      const md::DeviceReading r = dev.read(now);
      const std::int64_t t1 = tsmh::realtime::monotonic_now_ns();
      (*written_ns)[static_cast<std::size_t>(k % 1000)] = tsmh::realtime::monotonic_now_ns();
      dev.write_torque(md::JointArray{0.05 * std::sin(k * 0.01), (k % 1000 + 1) * 2e-4});
      const std::int64_t t2 = tsmh::realtime::monotonic_now_ns();
      read_ns.push_back(static_cast<double>(t1 - t0));
      write_ns.push_back(static_cast<double>(t2 - t1));
      if (k >= unplug_at && detected_after < 0 && r.status == md::DeviceStatus::kDisconnected) {
        detected_after = k - unplug_at;
      }
      if (k > unplug_at + 100 && recovered_after < 0 && r.status == md::DeviceStatus::kOk) {
        recovered_after = k - (unplug_at + 100);
        dev.set_enabled(true);
      }
      if (r.status == md::DeviceStatus::kOk) {
        age_us.push_back((now - r.t_ns) * 1e-3);
        fresh += r.fresh ? 1 : 0;
      }
      const bool streaming = k > 10 && (k < unplug_at || k > unplug_at + 200);
      if (streaming && r.sequence > 0) {
        streaming_age_us.push_back((now - r.t_ns) * 1e-3);
        stale_ticks += r.stale ? 1 : 0;
      }
    }
    const md::ConsoleStats s = dev.stats();
    print("reading age at read()", "us", percentiles(age_us));
    print("read() cost", "ns", percentiles(read_ns));
    print("write_torque() cost", "ns", percentiles(write_ns));
    print("loop wake-up lateness", "us", percentiles(late_us));
    std::vector<double> latency;
    bus->with_firmware([&](md::Firmware&) { latency = *latency_us; });
    print("write_torque() -> motor current", "us", percentiles(latency));
    std::printf(
        "  fresh readings %d of %zu OK ticks; reports %llu, lost %llu, bad %llu, outputs %llu\n",
        fresh, age_us.size(), static_cast<unsigned long long>(s.reports),
        static_cast<unsigned long long>(s.lost_reports),
        static_cast<unsigned long long>(s.bad_reports),
        static_cast<unsigned long long>(s.outputs_sent));
    std::printf("  unplug seen by the loop after %d tick(s); replug back to OK after %d ms\n",
                detected_after, recovered_after);
    print("sample age (device clock), streaming", "us", percentiles(streaming_age_us));
    std::printf("  stale ticks while streaming (bound %.1f ms): %d of %zu; late reports %llu\n",
                static_cast<double>(dev.freshness_bound_ns()) * 1e-6, stale_ticks,
                streaming_age_us.size(), static_cast<unsigned long long>(s.late_reports));
    std::printf("  ticks a bound of N periods would call stale:");
    for (const double n : {1.5, 2.0, 3.0, 5.0, 10.0}) {
      const auto over = std::count_if(streaming_age_us.begin(), streaming_age_us.end(),
                                      [n](double a) { return a > n * 1000.0; });
      std::printf("  N=%.1f: %ld", n, static_cast<long>(over));
    }
    std::printf("  (of %zu)\n", streaming_age_us.size());
    dev.close();
  }

  std::printf("== sim device, simulated time (palpate, feedback from a wall)\n");
  {
    md::SimSettings s;
    s.simulated_time = true;
    md::SimDevice dev(s);
    dev.open();
    dev.set_enabled(true);
    const int n = 200'000;
    const double per_tick = ns_per_op(n, [&](int k) {
      const md::DeviceReading r = dev.read(static_cast<std::int64_t>(k) * 1'000'000);
      dev.write_torque(md::JointArray{-2.0 * std::max(0.0, r.q[0] - 0.1), 0.0});
    });
    std::printf("  %.0f ns per 1 ms tick: %.0fx faster than real time\n", per_tick, 1e6 / per_tick);
  }
  return 0;
}
