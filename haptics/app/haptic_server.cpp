// haptic-server: the 1 kHz haptic loop (docs/haptic-server.md).
//
//   haptic-server --config server.yaml [--lcm-url URL] [--key FILE | --insecure] [--duration S]
//                 [--feedback estimated|naive|none] [--trace F] [--report F]
//   haptic-server --list-devices
//   haptic-server --config server.yaml --request-recalibration
//
// Exit paths: any catchable terminating signal (bridge/stop_signals.hpp),
// --duration, or any error after the device is open: each writes zero
// torque and disables the device before exiting. The core-dumping signals
// (SIGSEGV, SIGABRT, ...) go to a handler that sends prepared zero-torque
// and hold messages first (crash_outputs.hpp, bridge/crash_stop.hpp).

#include <pthread.h>
#include <signal.h>
#include <sys/mman.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <iostream>
#include <optional>
#include <stdexcept>

#include "bridge/host_only.hpp"
#include "bridge/lcm_url.hpp"
#include "bridge/link_security.hpp"
#include "bridge/stop_signals.hpp"
#include "calibration_log.hpp"
#include "crash_outputs.hpp"
#include "estimator/model_io.hpp"
#include "files/cli_numbers.hpp"
#include "files/distinct_outputs.hpp"
#include "haptics/evaluation.hpp"
#include "haptics/lcm_slave_link.hpp"
#include "haptics/loop_runner.hpp"
#include "haptics/server_config.hpp"
#include "lcm_device_auth.hpp"
#include "master_devices/builtin_drivers.hpp"
#include "master_devices/device.hpp"
#include "master_devices/lcm_device.hpp"
#include "master_devices/registry.hpp"
#include "realtime/clock.hpp"
#include "realtime/joint_names.hpp"
#include "request_recalibration.hpp"
#include "server_say.hpp"
#include "tsmh/cli_words.hpp"
#include "tsmh/version.hpp"

namespace {

using namespace tsmh;

struct Options {
  std::string config;
  std::string lcm_url;
  std::optional<std::string> prefix;
  std::optional<double> duration;
  std::optional<std::string> feedback;
  std::optional<double> rate;
  std::string trace;
  std::string report;
  bool list_devices = false;
  bool request_recalibration = false;
  bool quiet = false;
  bridge::LinkSecurityOptions link;  ///< --key, --insecure
};

// Exit status (docs/haptic-server.md, "Exit status"): 0 only for a clean
// session; a script or a supervisor tells the others apart by the code.
constexpr int kExitClean = 0;
constexpr int kExitError = 1;    // an unexpected error while running
constexpr int kExitConfig = 2;   // bad command line or configuration: nothing was started
constexpr int kExitDevice = 3;   // the master device could not be opened
constexpr int kExitFault = 4;    // the session went into FAULT (at any time)
constexpr int kExitNoSlave = 5;  // no SLAVE_STATE was ever used: nothing was rendered

// The master device could not be created or opened: the drivers' own error
// type, so a driver's DeviceError and the wrappers below exit alike (3).
using master_devices::DeviceError;

std::string seconds_text(double s) {
  char b[32];
  std::snprintf(b, sizeof b, s < 10 ? "%.1f s" : "%.0f s", s);
  return b;
}

std::string us_text(double us) {
  char b[32];
  if (us < 1000.0)
    std::snprintf(b, sizeof b, "%.0f us", us);
  else
    std::snprintf(b, sizeof b, "%.1f ms", us * 1e-3);
  return b;
}

/// Logs what the loop thread reports through LoopEvents (it never prints
/// itself): estimator re-initialisations, loss and return of the estimate,
/// state changes with the fault reason, stalls, a slave that sends nothing;
/// and, on a terminal, a live status line once a second. Main thread only.
class EventLog {
 public:
  struct Context {
    std::string slave_channel;  ///< e.g. ARM1_SLAVE_STATE
    std::string url;
    double slave_timeout_s = 1.0;
    std::string feedback;
    int joints = 0;
    bool live = false;  ///< stderr is a terminal and not --quiet
  };
  EventLog(haptics::LoopEvents& events, Context ctx, std::int64_t start_ns)
      : events_(events), ctx_(std::move(ctx)), start_ns_(start_ns), slave_seen_ns_(start_ns) {}

  void poll() {
    const std::int64_t now = tsmh::realtime::monotonic_now_ns();
    watch_slave(now);  // before the FAULT it causes
    const auto resets = events_.estimator_resets.load(std::memory_order_relaxed);
    if (resets != resets_) {
      say("slave clock jumped by %.6f s: estimators re-initialised (%llu so far)",
          static_cast<double>(events_.last_reset_jump_us.load()) * 1e-6,
          static_cast<unsigned long long>(resets));
      resets_ = resets;
    }
    const auto lost = events_.estimate_lost_joints.load(std::memory_order_relaxed);
    if (lost != lost_) {
      if (lost != 0)
        say("torque estimate lost (joint mask 0x%x): holding and fading the last valid one, "
            "FAULT if it lasts",
            lost);
      else
        say("torque estimate valid again on every joint");
      lost_ = lost;
    }
    const auto state = static_cast<haptics::LoopState>(events_.state.load());
    if (state != state_) {
      if (state == haptics::LoopState::kFault)
        say("FAULT: %s",
            std::string(to_string(static_cast<haptics::FaultReason>(events_.fault.load())))
                .c_str());
      state_ = state;
    }
    const std::int64_t worst = events_.worst_lateness_ns.exchange(0);
    if (worst > 10'000'000)
      say("warning: a tick started %.1f ms late (overruns %llu)", static_cast<double>(worst) * 1e-6,
          static_cast<unsigned long long>(events_.overruns.load()));
    if (ctx_.live && now >= next_live_ns_) {
      live_line(now);
      next_live_ns_ = now + 1'000'000'000;
    }
  }

  /// Removes the live line (before the exit summary).
  void clear() {
    if (live_shown_) std::fputs("\r\033[K", stderr);
    live_shown_ = false;
  }

 private:
  __attribute__((format(printf, 2, 3))) void say(const char* fmt, ...) {
    va_list args;
    va_start(args, fmt);
    haptic_server::vsay(live_shown_, fmt, args);
    va_end(args);
    live_shown_ = false;
  }

  // No fresh SLAVE_STATE for a second: say so at once (the operator otherwise
  // sees nothing at all), then every 5 s while it lasts, and when it returns.
  void watch_slave(std::int64_t now) {
    const std::uint64_t samples = events_.slave_samples.load(std::memory_order_relaxed);
    if (samples != slave_samples_) {
      if (slave_warned_)
        say("SLAVE_STATE arriving again on '%s' after %s without", ctx_.slave_channel.c_str(),
            seconds_text(static_cast<double>(now - slave_seen_ns_) * 1e-9).c_str());
      slave_samples_ = samples;
      slave_seen_ns_ = now;
      slave_warned_ = false;
      return;
    }
    const double silent_s = static_cast<double>(now - slave_seen_ns_) * 1e-9;
    if (silent_s < 1.0 || now < next_slave_warning_ns_) return;
    if (samples == 0)
      say("no SLAVE_STATE on '%s' (%s) for %s since start: is the slave running, on this URL and "
          "prefix? No torque is rendered; FAULT after %s without it",
          ctx_.slave_channel.c_str(), ctx_.url.c_str(), seconds_text(silent_s).c_str(),
          seconds_text(ctx_.slave_timeout_s).c_str());
    else
      say("no fresh SLAVE_STATE on '%s' for %s: torque faded to zero%s", ctx_.slave_channel.c_str(),
          seconds_text(silent_s).c_str(),
          silent_s > ctx_.slave_timeout_s ? ", FAULT (slave state lost)" : "");
    slave_warned_ = true;
    next_slave_warning_ns_ = now + 5'000'000'000;
  }

  // One compact line, rewritten in place: time, rate, lateness, state,
  // feedback and the torque on the master, the slave sample's age.
  void live_line(std::int64_t now) {
    char line[256];
    int n = std::snprintf(
        line, sizeof line, "%s  %.1f Hz  late p99 %s max %s  %s  %s",
        seconds_text(static_cast<double>(now - start_ns_) * 1e-9).c_str(), events_.rate_hz.load(),
        us_text(events_.lateness_p99_us.load()).c_str(),
        us_text(events_.lateness_max_us.load()).c_str(),
        std::string(to_string(static_cast<haptics::LoopState>(events_.state.load()))).c_str(),
        ctx_.feedback.c_str());
    n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), "  torque");
    for (int j = 0; j < ctx_.joints && n < 200; ++j)
      n += std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), " %+.3f",
                         events_.torque_nm[static_cast<std::size_t>(j)].load());
    const double age = events_.slave_age_ms.load();
    if (n < 220) {
      if (age < 0)
        std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), " N m  no slave yet");
      else
        std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n),
                      " N m  slave age %.1f ms", age);
    }
    std::fprintf(stderr, "\r\033[Khaptic-server: %s", line);
    std::fflush(stderr);
    live_shown_ = true;
  }

  haptics::LoopEvents& events_;
  Context ctx_;
  std::int64_t start_ns_;
  std::uint64_t resets_ = 0;
  std::uint32_t lost_ = 0;
  haptics::LoopState state_ = haptics::LoopState::kDisabled;
  std::uint64_t slave_samples_ = 0;
  std::int64_t slave_seen_ns_;
  std::int64_t next_slave_warning_ns_ = 0;
  bool slave_warned_ = false;
  std::int64_t next_live_ns_ = 0;
  bool live_shown_ = false;
};

/// Waits for a stop signal or the runner finishing, logging loop events and
/// keeping the crash messages fresh every 50 ms. Returns the signal or 0.
int wait_for_stop(const sigset_t& set, const haptics::LoopRunner& runner, EventLog& log,
                  haptic_server::CalibrationLog& calibration, haptic_server::CrashOutputs& crash,
                  haptics::HapticLoop& loop) {
  while (!runner.finished()) {
    // Another session on the slave or master link: the session is over for
    // good (the loop is in FAULT, torque zero); stop as on a signal.
    const auto fault = static_cast<haptics::FaultReason>(loop.events().fault.load());
    if (fault == haptics::FaultReason::kSlaveSession ||
        fault == haptics::FaultReason::kMasterSession) {
      log.poll();
      return 0;
    }
    timespec timeout{0, 50'000'000};
    const int sig = sigtimedwait(&set, nullptr, &timeout);
    if (sig > 0) return sig;
    log.poll();
    const std::int64_t now = tsmh::realtime::monotonic_now_ns();
    calibration.poll(now);
    crash.refresh(now);
  }
  return 0;
}

/// `lcm_auth`: the link key's authentication for the lcm driver's
/// MASTER_STATE / MASTER_FORCE (null: unauthenticated).
master_devices::DriverRegistry make_registry(
    std::shared_ptr<master_devices::LcmMessageAuth> lcm_auth = nullptr) {
  master_devices::DriverRegistry registry;
  master_devices::register_builtin_drivers(registry);
  master_devices::register_lcm_driver(registry, master_devices::monotonic_clock(),
                                      std::move(lcm_auth));
  return registry;
}

int list_devices() {
  const auto registry = make_registry();
  std::cout << master_devices::format_connected(registry.list_connected());
  return 0;
}

/// The `lcm` master device listens where the server's own link does
/// (--lcm-url, else the config's lcm.url, else $LCM_DEFAULT_URL, else the
/// default) unless its settings name a `url`: one flag moves the whole run.
void lcm_device_follows_link_url(haptics::ServerConfig& cfg, const std::string& link_url) {
  const YAML::Node& settings = cfg.device_settings;
  if (cfg.device_driver == "lcm" && !settings["url"]) cfg.device_settings["url"] = link_url;
}

/// The `lcm` master driver's own LCM link (its `url` setting, else the
/// server's: lcm_device_follows_link_url): the same rules as the bridge's. No key on a network URL
/// is refused without --insecure; on udpm ttl=0 its receive socket is confined to this host like
/// the Receiver's (bridge/host_only.hpp).
void confine_lcm_device(const haptics::ServerConfig& cfg, const bridge::LinkSecurityOptions& link,
                        const bridge::LinkSecurity& security) {
  const YAML::Node url_node = cfg.device_settings["url"];
  const std::string url =
      bridge::resolve_lcm_url(url_node && url_node.IsScalar() ? url_node.as<std::string>() : "");
  if (!security.key && !link.insecure && !bridge::is_host_local_url(url))
    throw bridge::LinkKeyError(
        "the lcm master device's URL '" + url +
        "' is reachable from other hosts and there is no link key (create "
        "one with `tsm-link keygen`, or pass --insecure on an isolated network)");
  if (const auto port = bridge::host_only_udpm_port(url)) {
    if (bridge::restrict_udp_port_to_host(*port) == 0)
      throw DeviceError("lcm: cannot confine the master device's LCM socket for '" + url +
                        "' to this host");
  }
}

/// The exit summary, printed once. Every figure says what it counts and what
/// is normal, so an operator can read it without the source.
/// What the oscillation detector and the passivity controller did.
void print_delay_summary(const haptics::HapticLoop& loop) {
  const auto& c = loop.counters();
  double w_min = 0.0, dissipated = 0.0;
  for (int j = 0; j < loop.joints(); ++j) {
    w_min = j == 0 ? loop.passivity(j).observed_energy()
                   : std::min(w_min, loop.passivity(j).observed_energy());
    dissipated += loop.passivity(j).dissipated();
  }
  std::fprintf(stderr,
               "  delay:  oscillation trips %llu (%llu ticks faded); passivity %s: controller "
               "active %llu ticks, dissipated %.4f J, observed energy W_M at the end (lowest "
               "joint) %.4f J\n",
               static_cast<unsigned long long>(c.oscillation_trips),
               static_cast<unsigned long long>(c.oscillation_ticks),
               loop.passivity_enabled() ? "on" : "off",
               static_cast<unsigned long long>(c.passivity_ticks), dissipated, w_min);
}

// One line per keyed session: whom it was bound to, and who ended it.
void print_session(const char* what, const bridge::LinkSession& s) {
  using ull = unsigned long long;
  std::fprintf(stderr, "  session %s: %s", what, bridge::to_string(s.state()));
  if (s.peer() != 0) std::fprintf(stderr, ", bound to %016llx", static_cast<ull>(s.peer()));
  if (s.state() == bridge::SessionState::kFault) {
    const auto f = s.fault();
    std::fprintf(stderr,
                 "; ended by another session: sender %016llx naming %016llx (%llu such messages)",
                 static_cast<ull>(f.sender_id), static_cast<ull>(f.names),
                 static_cast<ull>(s.other_session()));
  }
  std::fprintf(stderr, "; this end %016llx\n", static_cast<ull>(s.my_id()));
}

void print_summary(const haptics::HapticLoop& loop, const haptics::LcmSlaveLink& link,
                   const haptics::LcmDeviceSessionView* master_session,
                   const std::string& slave_channel, double seconds, int exit_code,
                   const char* verdict) {
  const auto lat = loop.lateness().summary();
  const auto cmp = loop.compute().summary();
  const auto& c = loop.counters();
  const auto st = link.state_stats();
  using ull = unsigned long long;
  std::fprintf(stderr, "haptic-server: summary of %.1f s\n", seconds);
  std::fprintf(stderr,
               "  loop:   %llu ticks at %.3f Hz (nominal %.0f); %llu deadlines skipped (overruns); "
               "lateness against the schedule p50 %s, p99 %s, p99.9 %s, max %s; compute p99 %s\n",
               static_cast<ull>(c.ticks), loop.measured_rate_hz(), loop.rate_hz(),
               static_cast<ull>(c.overruns), us_text(lat.p50_us).c_str(),
               us_text(lat.p99_us).c_str(), us_text(lat.p999_us).c_str(),
               us_text(lat.max_us).c_str(), us_text(cmp.p99_us).c_str());
  const double rate = seconds > 0 ? static_cast<double>(st.accepted) / seconds : 0.0;
  std::fprintf(stderr,
               "  slave:  '%s': %llu accepted (%.1f per s), %llu used by the loop (the newest at "
               "each tick); %llu rejected, %llu duplicates, %llu late/reordered (dropped)\n",
               slave_channel.c_str(), static_cast<ull>(st.accepted), rate,
               static_cast<ull>(c.slave_samples), static_cast<ull>(st.rejected()),
               static_cast<ull>(st.duplicates), static_cast<ull>(st.reordered));
  if (st.rejected() > 0) {
    // By reason, so a forged or foreign-key stream (unauthenticated, bad_mac,
    // stale, replayed) reads differently from a broken slave.
    std::string reasons;
    for (int i = 0; i < bridge::kRejectReasons; ++i) {
      const auto reason = static_cast<bridge::RejectReason>(i);
      if (st.rejected(reason) == 0) continue;
      reasons += reasons.empty() ? "" : ", ";
      reasons +=
          std::string(bridge::reason_name(reason)) + " " + std::to_string(st.rejected(reason));
    }
    std::fprintf(stderr, "          rejected by reason: %s\n", reasons.c_str());
  }
  std::fprintf(stderr,
               "          seq gaps %llu (%llu messages missing: the slave's seq jumped, i.e. "
               "messages lost on the way or rejected; 0 is normal on one host)\n",
               static_cast<ull>(st.seq_gaps), static_cast<ull>(st.seq_missing));
  if (st.restarts > 0 || st.resyncs > 0)
    std::fprintf(
        stderr,
        "          restarts %llu (seq went back while utime went on: the slave restarted%s), "
        "re-bases %llu\n",
        static_cast<ull>(st.restarts),
        st.restarts > 10 ? "; this many: two slaves publishing on one channel?" : "",
        static_cast<ull>(st.resyncs));
  if (st.latency.count > 0)
    std::fprintf(stderr,
                 "          one-way latency (arrival - the slave's utime, one host clock) p50 %s, "
                 "p99 %s (to 12.5 %%), max %s; normal on one host: under 1 ms\n",
                 us_text(st.latency.p50_us).c_str(), us_text(st.latency.p99_us).c_str(),
                 us_text(st.latency.max_us).c_str());
  if (st.discarded_before_start > 0)
    std::fprintf(stderr,
                 "          %llu messages queued before the loop started were discarded unread "
                 "(not counted above)\n",
                 static_cast<ull>(st.discarded_before_start));
  std::fprintf(stderr,
               "  safety: ticks faded (slave stale, or ramping in over recover_ms, at start too) "
               "%llu, saturated %llu, rate-limited %llu; non-finite "
               "requests %llu; estimate lost %llu ticks; estimator resets %llu; faults %llu\n",
               static_cast<ull>(c.stale_ticks), static_cast<ull>(c.saturated_ticks),
               static_cast<ull>(c.rate_limited_ticks), static_cast<ull>(c.nonfinite_requests),
               static_cast<ull>(c.estimate_lost_ticks), static_cast<ull>(c.estimator_resets),
               static_cast<ull>(c.faults));
  print_delay_summary(loop);
  if (link.session() != nullptr) print_session("slave ", *link.session());
  if (master_session != nullptr) print_session("master", master_session->session());
  std::fprintf(stderr, "  end:    state %s; exit %d (%s)\n",
               std::string(to_string(loop.state())).c_str(), exit_code, verdict);
}

/// The exit code of a session that ran (see kExit*).
int session_exit_code(const haptics::HapticLoop& loop, const char** verdict) {
  const auto& c = loop.counters();
  // Another session on the link says the most: the session could not hold.
  if (loop.fault() == haptics::FaultReason::kSlaveSession ||
      loop.fault() == haptics::FaultReason::kMasterSession) {
    *verdict = "ended in FAULT";
    return kExitFault;
  }
  if (c.slave_samples == 0) {
    *verdict = "no SLAVE_STATE was ever received: nothing was rendered";
    return kExitNoSlave;
  }
  if (loop.state() == haptics::LoopState::kFault || c.faults > 0) {
    *verdict = loop.state() == haptics::LoopState::kFault ? "ended in FAULT"
                                                          : "went into FAULT during the session";
    return kExitFault;
  }
  *verdict = "clean session";
  return kExitClean;
}

// The command line's overrides of the configuration.
void apply_command_line(haptics::ServerConfig& cfg, const Options& o) {
  if (o.duration) cfg.duration_s = *o.duration;
  if (o.feedback) cfg.loop.source = haptics::feedback_source_from_string(*o.feedback);
  if (o.rate) cfg.loop.set_rate(*o.rate);  // in range: the option's check
  if (o.prefix) cfg.lcm_prefix = *o.prefix;
  if (!o.trace.empty()) cfg.evaluation.trace = o.trace;
  if (!o.report.empty()) cfg.evaluation.report = o.report;
}

// One estimator per joint; a bad params file fails here, before anything
// is opened.
std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> make_estimators(
    const haptics::ServerConfig& cfg) {
  std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> estimators;
  for (const auto& j : cfg.joints) {
    try {
      estimators.push_back(std::make_unique<estimator::DistalTorqueEstimator>(
          estimator::load_model(j.params), j.radius_m, j.estimator.differentiator(),
          j.estimator.start_state));
    } catch (const std::exception& e) {
      throw haptics::ConfigError(cfg.source + ": joint '" + j.name + "': " + e.what());
    }
  }
  return estimators;
}

std::unique_ptr<master_devices::Device> create_device(
    const haptics::ServerConfig& cfg, const master_devices::DriverRegistry& registry) {
  master_devices::DriverContext ctx{cfg.source, "device.settings",
                                    std::filesystem::path(cfg.source).parent_path()};
  try {
    return registry.create(cfg.device_driver, cfg.device_settings, ctx);
  } catch (const config::ConfigError&) {
    throw;  // a bad setting: exit 2 with the file, field and line
  } catch (const std::exception& e) {
    throw DeviceError(std::string("cannot create the master device (") + cfg.device_driver +
                      "): " + e.what());
  }
}

// The configured torque limit never exceeds what the device can take.
void cap_torque_to_device(haptics::ServerConfig& cfg, const master_devices::DeviceSpec& spec) {
  for (int j = 0; j < cfg.loop.joints; ++j) {
    const double peak = spec.peak_torque_nm[static_cast<std::size_t>(j)];
    auto& lim = cfg.loop.limits[static_cast<std::size_t>(j)];
    if (peak > 0.0 && lim.max_torque_nm > peak) {
      std::fprintf(
          stderr,
          "haptic-server: %s: max_torque_nm %.3g above the device's peak %.3g; using %.3g\n",
          realtime::joint_name(j).c_str(), lim.max_torque_nm, peak, peak);
      lim.max_torque_nm = peak;
    }
  }
}

// No output may be an input of the run (its configuration, the link key,
// a joint's params file, the device profile) or the other output: `--trace
// link.key` replaced the key, `--trace X --report X` lost the trace. Checked
// before anything is opened (files/distinct_outputs.hpp); exit 2.
void check_outputs(const haptics::ServerConfig& cfg, const Options& o) {
  std::vector<files::NamedInput> inputs{{"the configuration", o.config}};
  try {
    if (const auto key = bridge::find_key_file(o.link.key_file, std::getenv(bridge::kLinkKeyEnv),
                                               std::getenv("XDG_CONFIG_HOME"), std::getenv("HOME")))
      inputs.push_back({"the link key", *key});
  } catch (const std::exception&) {
    // resolve_link_security() reports a key that cannot be found.
  }
  const auto presets = estimator::preset_names();
  for (const auto& j : cfg.joints) {
    if (std::find(presets.begin(), presets.end(), j.params) == presets.end())
      inputs.push_back({"the params of joint '" + j.name + "'", j.params});
  }
  const YAML::Node profile = cfg.device_settings["profile"];
  if (profile && profile.IsScalar()) {
    std::filesystem::path file(profile.Scalar());
    if (file.is_relative()) file = std::filesystem::path(cfg.source).parent_path() / file;
    inputs.push_back({"the device profile", file});
  }
  const char* trace_role = o.trace.empty() ? "evaluation.trace" : "--trace";
  const char* report_role = o.report.empty() ? "evaluation.report" : "--report";
  try {
    files::check_distinct_outputs(
        inputs, {{trace_role, cfg.evaluation.trace}, {report_role, cfg.evaluation.report}});
  } catch (const files::FileError& e) {
    throw haptics::ConfigError(e.what());
  }
}

// Trace and report: rows stream to an unlinked spool file beside the output
// through a fixed ring (memory does not grow with the run). The output
// folders must exist: checked before anything is opened. nullptr: neither
// is asked for.
std::unique_ptr<haptics::TraceSpool> make_trace_spool(const haptics::ServerConfig& cfg) {
  if (cfg.evaluation.trace.empty() && cfg.evaluation.report.empty()) return nullptr;
  for (const std::string* out : {&cfg.evaluation.trace, &cfg.evaluation.report}) {
    if (out->empty()) continue;
    const auto folder = std::filesystem::path(*out).parent_path();
    std::error_code ec;
    if (!folder.empty() && !std::filesystem::is_directory(folder, ec))
      throw haptics::ConfigError(*out + ": the folder '" + folder.string() +
                                 "' does not exist (outputs are written into existing "
                                 "folders only)");
  }
  const std::string& first =
      cfg.evaluation.trace.empty() ? cfg.evaluation.report : cfg.evaluation.trace;
  return std::make_unique<haptics::TraceSpool>(
      cfg.loop.joints, std::filesystem::path(first).parent_path(),
      static_cast<std::uint64_t>(cfg.evaluation.max_trace_s * cfg.loop.rate_hz) + 16);
}

// After the loop: the trace mapped back from disk, written as CSV and
// evaluated into the report.
void write_trace_and_report(const haptics::HapticLoop& loop, haptics::TraceSpool& trace,
                            const haptics::ServerConfig& cfg,
                            const haptic_server::CalibrationLog& calibration, bool quiet) {
  // The loop is over: nothing needs locked memory any more, and the trace
  // is mapped back from disk (page cache, not locked).
  if (cfg.realtime.lock_memory) munlockall();
  const haptics::Trace recorded = trace.finish();
  const std::uint64_t spooled = trace.bytes_written();
  if (recorded.dropped() > 0)
    std::fprintf(stderr,
                 "haptic-server: warning: trace: %llu rows not recorded (past "
                 "evaluation.max_trace_s, or the writer fell %zu rows behind)\n",
                 static_cast<unsigned long long>(recorded.dropped()),
                 haptics::TraceSpool::kRingRows);
  if (!quiet)
    std::fprintf(stderr, "haptic-server: trace: %zu rows, %.1f MB spooled to disk\n",
                 recorded.size(), static_cast<double>(spooled) * 1e-6);
  if (!cfg.evaluation.trace.empty()) recorded.write_csv(cfg.evaluation.trace);
  if (cfg.evaluation.report.empty()) return;
  auto report = haptics::evaluate(loop, recorded, cfg);
  for (const auto& e : calibration.events())
    report.calibration.push_back(
        {e.t_s, e.kind, e.joint, e.scale, e.detail, e.scale_positive, e.scale_negative});
  for (int j = 0; j < cfg.loop.joints; ++j) {
    report.friction_scale.push_back(loop.calibration().applied_scale(j));
    report.friction_scale_positive.push_back(loop.calibration().applied_scale(j, false));
    report.friction_scale_negative.push_back(loop.calibration().applied_scale(j, true));
  }
  haptics::write_report(report, cfg.evaluation.report);
  if (!quiet) std::cerr << haptics::format_report(report);
}

int run(const Options& o, const sigset_t& stop_signals) {
  int exit_code = kExitClean;
  haptics::ServerConfig cfg = haptics::load_server_config(o.config);
  apply_command_line(cfg, o);
  check_outputs(cfg, o);
  auto estimators = make_estimators(cfg);

  haptics::LcmSlaveLinkConfig link_cfg;
  link_cfg.bridge.url = bridge::resolve_lcm_url(o.lcm_url.empty() ? cfg.lcm_url : o.lcm_url);
  link_cfg.bridge.prefix = cfg.lcm_prefix;
  // Only authenticated peers move the master (docs/bridge.md, "Authentication").
  const auto security = bridge::resolve_link_security(link_cfg.bridge.url, o.link);
  link_cfg.bridge.key = security.key;
  if (!security.key || !o.quiet)
    std::fprintf(stderr, "haptic-server: %s\n", security.notice.c_str());
  link_cfg.joints = cfg.loop.joints;
  link_cfg.state_limits = cfg.slave_limits;
  link_cfg.subscribe_truth = cfg.evaluation.truth;
  haptics::LcmSlaveLink link(link_cfg);

  const auto device_auth = haptics::make_lcm_device_auth(security.key);
  const auto registry = make_registry(device_auth);
  lcm_device_follows_link_url(cfg, link_cfg.bridge.url);
  std::unique_ptr<master_devices::Device> device = create_device(cfg, registry);
  haptics::check_against_device(cfg, device->spec());
  cap_torque_to_device(cfg, device->spec());
  std::unique_ptr<haptics::TraceSpool> trace = make_trace_spool(cfg);

  try {
    device->open();
  } catch (const std::exception& e) {
    throw DeviceError(std::string("cannot open the master device (") + cfg.device_driver + ", " +
                      device->spec().model + "): " + e.what());
  }
  if (cfg.device_driver == "lcm") confine_lcm_device(cfg, o.link, security);
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
    // The core-dumping signals: zero torque and a hold, best effort, before
    // the process ends as the kernel ends it (docs/haptic-server.md "Crash").
    std::optional<haptic_server::CrashOutputs> crash;
    crash.emplace(haptic_server::CrashOutputs::Setup{.link = link,
                                                     .link_url = link_cfg.bridge.url,
                                                     .joints = cfg.loop.joints,
                                                     .device = *device,
                                                     .driver = cfg.device_driver,
                                                     .device_auth = device_auth});
    if (!o.quiet && !crash->summary().empty())
      std::fprintf(stderr, "haptic-server: on a crash signal: %s\n", crash->summary().c_str());
    haptics::LoopRunner runner(loop, {cfg.loop.rate_hz, cfg.realtime.sched_fifo,
                                      cfg.realtime.priority, cfg.realtime.cpu, cfg.duration_s});
    const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
    runner.start();
    const auto& rt = runner.status();
    if (!rt.sched_fifo) std::fprintf(stderr, "haptic-server: warning: %s\n", rt.sched_note.c_str());
    if (!o.quiet)
      std::fprintf(
          stderr, "haptic-server: %d joints at %.0f Hz, feedback %s, device %s (%s), lcm %s%s%s\n",
          cfg.loop.joints, cfg.loop.rate_hz, std::string(to_string(cfg.loop.source)).c_str(),
          cfg.device_driver.c_str(), device->spec().model.c_str(), link_cfg.bridge.url.c_str(),
          cfg.lcm_prefix.empty() ? "" : " prefix ", cfg.lcm_prefix.c_str());
    const std::string slave_channel = cfg.lcm_prefix + "SLAVE_STATE";
    const bool live = !o.quiet && isatty(STDERR_FILENO) != 0;
    EventLog events(loop.events(),
                    {.slave_channel = slave_channel,
                     .url = link_cfg.bridge.url,
                     .slave_timeout_s = cfg.loop.slave_timeout_s,
                     .feedback = std::string(to_string(cfg.loop.source)),
                     .joints = cfg.loop.joints,
                     .live = live},
                    t0);
    std::vector<bool> paper_joints;
    for (const auto& jc : cfg.joints)
      paper_joints.push_back(jc.params == "paper");
    haptic_server::CalibrationLog calibration(
        loop.calibration(), t0, live,
        {.config_path = o.config,
         .master_has_calibrate_button = device->spec().has_calibrate_button},
        std::move(paper_joints));
    const int sig = wait_for_stop(stop_signals, runner, events, calibration, *crash, loop);
    events.poll();  // anything the loop reported in its last ticks
    calibration.poll(tsmh::realtime::monotonic_now_ns());
    events.clear();
    runner.stop();
    runner.join();  // the loop thread wrote zero torque on its way out
    crash.reset();  // before the sockets and descriptors it knows are closed
    const double seconds = static_cast<double>(tsmh::realtime::monotonic_now_ns() - t0) * 1e-9;
    link.goodbye();  // the slave holds and is free for the next server at once
    link.stop();
    device->close();
    if (sig)
      std::fprintf(stderr, "haptic-server: %s: torque zeroed, stopping\n",
                   bridge::signal_name(sig));
    const char* verdict = "";
    exit_code = session_exit_code(loop, &verdict);
    std::string verdict_text = verdict;
    if (exit_code == kExitFault && loop.state() == haptics::LoopState::kFault)
      verdict_text += std::string(": ") + std::string(to_string(loop.fault()));
    // The master session only when the lcm driver is the master device.
    const auto* master_session =
        cfg.device_driver == "lcm"
            ? dynamic_cast<const haptics::LcmDeviceSessionView*>(device_auth.get())
            : nullptr;
    print_summary(loop, link, master_session, slave_channel, seconds, exit_code,
                  verdict_text.c_str());
    if (const auto* lcm_device = dynamic_cast<const master_devices::LcmDevice*>(device.get());
        lcm_device != nullptr && lcm_device->rejected_messages() > 0)
      std::fprintf(stderr, "  device: %llu MASTER_STATE rejected, never used; the last: %s\n",
                   static_cast<unsigned long long>(lcm_device->rejected_messages()),
                   lcm_device->last_rejection().c_str());
    if (trace) write_trace_and_report(loop, *trace, cfg, calibration, o.quiet);
  } catch (...) {
    loop.shutdown();  // zero torque before anything else happens
    link.goodbye();
    device->close();
    throw;
  }
  return exit_code;
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
  app.set_version_flag("--version", tsmh::version_line("haptic-server"));
  Options o;
  app.add_option("--config", o.config, "Server configuration (YAML)");
  app.add_option("--lcm-url", o.lcm_url,
                 "LCM URL (default: $LCM_DEFAULT_URL, else udpm://239.255.76.67:7667?ttl=0)");
  app.add_option("--prefix", o.prefix,
                 "LCM channel prefix of the arm, e.g. ARM1_ (overrides lcm.prefix in the config)");
  app.add_option("--duration", o.duration,
                 "Stop after this many seconds (default: until SIGINT/SIGTERM)")
      ->check(files::finite_range(0.0, 1e7, "s"));
  app.add_option("--feedback", o.feedback, "What to render: estimated (default), naive, none")
      ->check(CLI::IsMember({"estimated", "naive", "none"}));
  app.add_option("--rate", o.rate, "Loop rate in Hz (1..4000)")
      ->check(files::finite_range(haptics::LoopConfig::kMinRateHz, haptics::LoopConfig::kMaxRateHz,
                                  "Hz"));
  app.add_option("--trace", o.trace, "Write a per-tick CSV trace here at exit");
  app.add_option("--report", o.report, "Write the JSON evaluation report here at exit");
  app.add_flag("--list-devices", o.list_devices,
               "List connected master devices matching known profiles");
  app.add_flag("--quiet", o.quiet, "Only warnings and the exit summary");
  app.add_option("--key", o.link.key_file, bridge::kKeyOptionHelp);
  app.add_flag("--insecure", o.link.insecure,
               "Run without a link key on a network LCM URL: anyone who reaches it can "
               "command the robot and the master (isolated networks only)");
  app.add_flag("--request-recalibration", o.request_recalibration,
               "Send one CALIBRATION_REQUEST for every joint of --config to the server running "
               "with it, and exit");
  // A typo is named with the nearest option (tsmh/cli_words.hpp).
  if (tsmh::cli_words::check_words(app, argc, argv) != 0) return kExitConfig;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? kExitClean : kExitConfig;  // --help: 0; a bad option: 2
  }
  try {
    if (o.list_devices) return list_devices();
    if (o.config.empty()) {
      std::cerr
          << "haptic-server: error: --config FILE is required (see examples/demo/server.yaml)\n";
      return kExitConfig;
    }
    if (o.request_recalibration)
      return haptic_server::request_recalibration(o.config, o.lcm_url, o.prefix, o.link);
    return run(o, stop_signals);
  } catch (const haptics::ConfigError& e) {
    std::cerr << "haptic-server: error: " << e.what() << "\n";
    return kExitConfig;
  } catch (const bridge::LinkKeyError& e) {
    std::cerr << "haptic-server: error: " << e.what() << "\n";
    return kExitConfig;
  } catch (const bridge::LcmUrlError& e) {
    std::cerr << "haptic-server: error: " << e.what() << "\n";
    return kExitConfig;
  } catch (const DeviceError& e) {
    std::cerr << "haptic-server: error: " << e.what() << "\n";
    return kExitDevice;
  } catch (const std::exception& e) {
    std::cerr << "haptic-server: error: " << e.what() << "\n";
    return kExitError;
  }
}
