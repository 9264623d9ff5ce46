// haptic-server: the 1 kHz haptic loop (docs/haptic-server.md).
//
//   haptic-server --config server.yaml [--lcm-url URL] [--duration S]
//                 [--feedback estimated|naive|none] [--trace F] [--report F]
//   haptic-server --list-devices
//
// Exit paths: any catchable terminating signal (bridge/stop_signals.hpp),
// --duration, or any error after the device is open: each writes zero
// torque and disables the device before exiting.

#include <pthread.h>
#include <signal.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <optional>

#include "bridge/lcm_url.hpp"
#include "bridge/stop_signals.hpp"
#include "estimator/model_io.hpp"
#include "haptics/evaluation.hpp"
#include "haptics/lcm_slave_link.hpp"
#include "haptics/loop_runner.hpp"
#include "haptics/server_config.hpp"
#include "master_devices/builtin_drivers.hpp"
#include "master_devices/lcm_device.hpp"
#include "master_devices/registry.hpp"

namespace {

using namespace tsmh;

struct Options {
  std::string config;
  std::string lcm_url;
  std::optional<double> duration;
  std::optional<std::string> feedback;
  std::optional<double> rate;
  std::string trace;
  std::string report;
  bool list_devices = false;
  bool quiet = false;
};

/// Logs what the loop thread reports through LoopEvents (it never prints
/// itself): estimator re-initialisations, loss and return of the estimate,
/// state changes with the fault reason, and stalls.
class EventLog {
 public:
  explicit EventLog(haptics::LoopEvents& events) : events_(events) {}
  void poll() {
    const auto resets = events_.estimator_resets.load(std::memory_order_relaxed);
    if (resets != resets_) {
      std::fprintf(stderr,
                   "haptic-server: slave clock jumped by %.6f s: estimators re-initialised (%llu "
                   "so far)\n",
                   static_cast<double>(events_.last_reset_jump_us.load()) * 1e-6,
                   static_cast<unsigned long long>(resets));
      resets_ = resets;
    }
    const auto lost = events_.estimate_lost_joints.load(std::memory_order_relaxed);
    if (lost != lost_) {
      if (lost != 0)
        std::fprintf(stderr,
                     "haptic-server: torque estimate lost (joint mask 0x%x): holding and fading "
                     "the last valid one, FAULT if it lasts\n",
                     lost);
      else
        std::fprintf(stderr, "haptic-server: torque estimate valid again on every joint\n");
      lost_ = lost;
    }
    const auto state = static_cast<haptics::LoopState>(events_.state.load());
    if (state != state_) {
      if (state == haptics::LoopState::kFault)
        std::fprintf(stderr, "haptic-server: FAULT: %s\n",
                     std::string(to_string(static_cast<haptics::FaultReason>(events_.fault.load())))
                         .c_str());
      state_ = state;
    }
    const std::int64_t worst = events_.worst_lateness_ns.exchange(0);
    if (worst > 10'000'000)
      std::fprintf(stderr, "haptic-server: warning: a tick started %.1f ms late (overruns %llu)\n",
                   static_cast<double>(worst) * 1e-6,
                   static_cast<unsigned long long>(events_.overruns.load()));
  }

 private:
  haptics::LoopEvents& events_;
  std::uint64_t resets_ = 0;
  std::uint32_t lost_ = 0;
  haptics::LoopState state_ = haptics::LoopState::kDisabled;
};

/// Waits for a stop signal or the runner finishing, logging loop events every
/// 50 ms. Returns the signal or 0.
int wait_for_stop(const sigset_t& set, const haptics::LoopRunner& runner, EventLog& log) {
  while (!runner.finished()) {
    timespec timeout{0, 50'000'000};
    const int sig = sigtimedwait(&set, nullptr, &timeout);
    if (sig > 0) return sig;
    log.poll();
  }
  return 0;
}

master_devices::DriverRegistry make_registry() {
  master_devices::DriverRegistry registry;
  master_devices::register_builtin_drivers(registry);
  master_devices::register_lcm_driver(registry);
  return registry;
}

int list_devices() {
  const auto registry = make_registry();
  std::cout << master_devices::format_connected(registry.list_connected());
  return 0;
}

void print_summary(const haptics::HapticLoop& loop, const haptics::LcmSlaveLink& link,
                   double seconds) {
  const auto lat = loop.lateness().summary();
  const auto cmp = loop.compute().summary();
  const auto& c = loop.counters();
  const auto st = link.state_stats();
  std::fprintf(
      stderr,
      "haptic-server: ran %.1f s, %llu ticks at %.3f Hz (nominal %.0f), overruns %llu\n"
      "  lateness us: p50 %.1f  p99 %.1f  p99.9 %.1f  max %.1f;  compute p99 %.1f us\n"
      "  slave: %llu samples used, %llu accepted, %llu rejected, %llu seq gaps, latency p99 "
      "%.0f us\n"
      "  safety: stale %llu ticks, saturated %llu, rate-limited %llu, non-finite %llu, estimate "
      "lost %llu ticks, estimator resets %llu;  state %s\n",
      seconds, static_cast<unsigned long long>(c.ticks), loop.measured_rate_hz(), loop.rate_hz(),
      static_cast<unsigned long long>(c.overruns), lat.p50_us, lat.p99_us, lat.p999_us, lat.max_us,
      cmp.p99_us, static_cast<unsigned long long>(c.slave_samples),
      static_cast<unsigned long long>(st.accepted), static_cast<unsigned long long>(st.rejected()),
      static_cast<unsigned long long>(st.seq_gaps), st.latency.p99_us,
      static_cast<unsigned long long>(c.stale_ticks),
      static_cast<unsigned long long>(c.saturated_ticks),
      static_cast<unsigned long long>(c.rate_limited_ticks),
      static_cast<unsigned long long>(c.nonfinite_requests),
      static_cast<unsigned long long>(c.estimate_lost_ticks),
      static_cast<unsigned long long>(c.estimator_resets),
      std::string(to_string(loop.state())).c_str());
}

int run(const Options& o, const sigset_t& stop_signals) {
  haptics::ServerConfig cfg = haptics::load_server_config(o.config);
  if (o.duration) cfg.duration_s = *o.duration;
  if (o.feedback) cfg.loop.source = haptics::feedback_source_from_string(*o.feedback);
  if (o.rate) {
    if (!(*o.rate >= 1.0 && *o.rate <= 4000.0))
      throw haptics::ConfigError("--rate: must be within 1..4000 Hz");
    cfg.loop.rate_hz = *o.rate;
    cfg.loop.status_every = std::max(1, static_cast<int>(std::lround(*o.rate / 100.0)));
  }
  if (!o.trace.empty()) cfg.evaluation.trace = o.trace;
  if (!o.report.empty()) cfg.evaluation.report = o.report;

  // Estimators first: a bad params file must fail before anything is opened.
  std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> estimators;
  for (const auto& j : cfg.joints) {
    try {
      estimators.push_back(std::make_unique<estimator::DistalTorqueEstimator>(
          estimator::load_model(j.params), j.radius_m,
          estimator::DifferentiatorConfig{.sign_mode = j.sign}, j.start_state));
    } catch (const std::exception& e) {
      throw haptics::ConfigError(cfg.source + ": joint '" + j.name + "': " + e.what());
    }
  }

  haptics::LcmSlaveLinkConfig link_cfg;
  link_cfg.bridge.url = bridge::resolve_lcm_url(o.lcm_url.empty() ? cfg.lcm_url : o.lcm_url);
  link_cfg.bridge.prefix = cfg.lcm_prefix;
  link_cfg.joints = cfg.loop.joints;
  link_cfg.state_limits = cfg.slave_limits;
  link_cfg.subscribe_truth = cfg.evaluation.truth;
  haptics::LcmSlaveLink link(link_cfg);

  const auto registry = make_registry();
  master_devices::DriverContext ctx{cfg.source, "device.settings",
                                    std::filesystem::path(cfg.source).parent_path()};
  auto device = registry.create(cfg.device_driver, cfg.device_settings, ctx);
  haptics::check_against_device(cfg, device->spec());
  // The configured torque limit never exceeds what the device can take.
  for (int j = 0; j < cfg.loop.joints; ++j) {
    const double peak = device->spec().peak_torque_nm[static_cast<std::size_t>(j)];
    auto& lim = cfg.loop.limits[static_cast<std::size_t>(j)];
    if (peak > 0.0 && lim.max_torque_nm > peak) {
      std::fprintf(
          stderr,
          "haptic-server: joint %d: max_torque_nm %.3g above the device's peak %.3g; using %.3g\n",
          j, lim.max_torque_nm, peak, peak);
      lim.max_torque_nm = peak;
    }
  }

  std::unique_ptr<haptics::Trace> trace;
  if (!cfg.evaluation.trace.empty() || !cfg.evaluation.report.empty())
    trace = std::make_unique<haptics::Trace>(
        cfg.loop.joints,
        static_cast<std::size_t>(cfg.evaluation.max_trace_s * cfg.loop.rate_hz) + 16);

  device->open();
  haptics::HapticLoop loop(cfg.loop, *device, link, std::move(estimators), trace.get());
  try {
    if (cfg.realtime.lock_memory) {
      const std::string note = haptics::lock_memory();
      if (!note.empty()) std::fprintf(stderr, "haptic-server: warning: %s\n", note.c_str());
    }
    std::optional<haptics::CpuDmaLatency> dma;
    if (cfg.realtime.cpu_dma_latency) {
      dma.emplace();
      if (!dma->active()) std::fprintf(stderr, "haptic-server: warning: %s\n", dma->note().c_str());
    }
    link.start();
    haptics::LoopRunner runner(loop, {cfg.loop.rate_hz, cfg.realtime.sched_fifo,
                                      cfg.realtime.priority, cfg.realtime.cpu, cfg.duration_s});
    timespec t0{};
    clock_gettime(CLOCK_MONOTONIC, &t0);
    runner.start();
    const auto& rt = runner.status();
    if (!rt.sched_fifo) std::fprintf(stderr, "haptic-server: warning: %s\n", rt.sched_note.c_str());
    if (!o.quiet)
      std::fprintf(
          stderr, "haptic-server: %d joints at %.0f Hz, feedback %s, device %s (%s), lcm %s%s%s\n",
          cfg.loop.joints, cfg.loop.rate_hz, std::string(to_string(cfg.loop.source)).c_str(),
          cfg.device_driver.c_str(), device->spec().model.c_str(), link_cfg.bridge.url.c_str(),
          cfg.lcm_prefix.empty() ? "" : " prefix ", cfg.lcm_prefix.c_str());
    EventLog events(loop.events());
    const int sig = wait_for_stop(stop_signals, runner, events);
    runner.stop();
    runner.join();  // the loop thread wrote zero torque on its way out
    timespec t1{};
    clock_gettime(CLOCK_MONOTONIC, &t1);
    const double seconds =
        static_cast<double>(t1.tv_sec - t0.tv_sec) + (t1.tv_nsec - t0.tv_nsec) * 1e-9;
    link.stop();
    device->close();
    if (sig)
      std::fprintf(stderr, "haptic-server: %s: torque zeroed, stopping\n",
                   bridge::signal_name(sig));
    print_summary(loop, link, seconds);
    if (trace && !cfg.evaluation.trace.empty()) trace->write_csv(cfg.evaluation.trace);
    if (trace && !cfg.evaluation.report.empty()) {
      const auto report = haptics::evaluate(loop, *trace, cfg);
      haptics::write_report(report, cfg.evaluation.report);
      if (!o.quiet) std::cerr << haptics::format_report(report);
    }
  } catch (...) {
    loop.shutdown();  // zero torque before anything else happens
    device->close();
    throw;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Every catchable terminating signal (SIGHUP, SIGQUIT, SIGUSR1, ... not
  // only SIGINT/SIGTERM) is blocked before any thread exists, so in every
  // thread, and taken by sigtimedwait() in run(): all of them end through the
  // zero-torque path. SIGPIPE is ignored (write errors are reported where
  // they happen).
  const sigset_t stop_signals = tsmh::bridge::block_terminating_signals();
  CLI::App app{"haptic-server: 1 kHz haptic feedback for tendon-sheath driven robots"};
  Options o;
  app.add_option("--config", o.config, "Server configuration (YAML)");
  app.add_option("--lcm-url", o.lcm_url,
                 "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0)");
  app.add_option("--duration", o.duration,
                 "Stop after this many seconds (default: until SIGINT/SIGTERM)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--feedback", o.feedback, "What to render: estimated (default), naive, none")
      ->check(CLI::IsMember({"estimated", "naive", "none"}));
  app.add_option("--rate", o.rate, "Loop rate in Hz (1..4000)");
  app.add_option("--trace", o.trace, "Write a per-tick CSV trace here at exit");
  app.add_option("--report", o.report, "Write the JSON evaluation report here at exit");
  app.add_flag("--list-devices", o.list_devices,
               "List connected master devices matching known profiles");
  app.add_flag("--quiet", o.quiet, "Only warnings and the exit summary");
  CLI11_PARSE(app, argc, argv);
  try {
    if (o.list_devices) return list_devices();
    if (o.config.empty()) {
      std::cerr
          << "haptic-server: error: --config FILE is required (see examples/demo/server.yaml)\n";
      return 2;
    }
    return run(o, stop_signals);
  } catch (const haptics::ConfigError& e) {
    std::cerr << "haptic-server: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "haptic-server: error: " << e.what() << "\n";
    return 1;
  }
}
