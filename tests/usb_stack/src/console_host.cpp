// Host side of the driver cases: our console driver (`hid` over hidapi or
// `usb` over libusb, created through the driver registry as the server does)
// against the firmware on the gadget side of the dummy_hcd cable.
//
// Phases, each reported as RESULT <prefix>_<phase> lines:
//   list      the registry's device listing finds the console by VID/PID
//   open      open(): DEVICE_INFO and CALIBRATION handshake over the real control path
//   stream    a 1 kHz loop on absolute deadlines for --seconds, torque enabled:
//             input sequence, malformed reports, outputs, lateness (METRIC lines)
//   watchdog  the loop commands torque, then this whole process stops itself
//             (SIGSTOP: the host dies silently); the case script lets the
//             firmware judge its watchdog and continues us; the driver must
//             come back to OK. When our last output before the stop carried
//             no current (its input report was late, so the driver sent
//             zero), the firmware has nothing to cut: it asks for another
//             attempt (verdict file <mailbox>.watchdog: "retry"), at most 5.
//   unplug    --replugs times: unbind the gadget (write "" to --udc) while the
//             loop commands torque; from one loop cycle after the driver's
//             freshness bound has passed since the device's last input report
//             (the firmware records when it left, in --mailbox), read() must
//             say not OK with zero torque, and stay so; the driver's link
//             state must flip (what the kernel and the library take for it
//             is reported); rebind must be picked up again, the device
//             coming back disabled
//
// Usage: usb_stack_console_host --driver hid|usb --prefix P --udc FILE
//          --mailbox FILE [--udc-name dummy_udc.0] [--seconds 2] [--replugs 2]
//          [--stale-timeout-ms N] [--no-watchdog] [--set KEY=VALUE]...
// --set: a driver setting (YAML value), e.g. --set stale_periods=5

#include <signal.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <memory>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "device_mailbox.hpp"
#include "guest_report.hpp"
#include "loop_clock.hpp"
#include "master_devices/builtin_drivers.hpp"
#include "master_devices/console_device.hpp"
#include "master_devices/profile.hpp"
#include "master_devices/registry.hpp"
#include "realtime/clock.hpp"
#include "realtime/quantile.hpp"
#include "unplug.hpp"

namespace md = tsmh::master_devices;
using tsmh::usb_stack::exists;
using tsmh::usb_stack::LoopClock;
using tsmh::usb_stack::MailboxMap;
using tsmh::usb_stack::metric;
using tsmh::usb_stack::result;
using tsmh::usb_stack::sysfs_of;
using tsmh::usb_stack::UdcWriter;
using tsmh::usb_stack::UnplugWatch;

namespace {

constexpr std::int64_t kPeriodNs = 1'000'000;

struct Options {
  std::string driver = "hid";
  std::string prefix;
  std::string udc_file;
  std::string udc_name = "dummy_udc.0";
  std::string mailbox;
  double seconds = 2.0;
  int replugs = 2;
  long stale_timeout_ms = 0;  // 0: the driver's default
  bool watchdog = true;
  std::vector<std::pair<std::string, std::string>> settings;  ///< --set KEY=VALUE: driver settings
  double torque_nm = 0.01;                                    ///< rendered torque limit, N m
};

__attribute__((format(printf, 1, 2))) std::string fmt(const char* f, ...) {
  char b[1000];
  va_list args;
  va_start(args, f);
  std::vsnprintf(b, sizeof b, f, args);
  va_end(args);
  return b;
}

double ms(std::int64_t ns) {
  return static_cast<double>(ns) * 1e-6;
}

class Host {
 public:
  Host(Options o, md::DriverRegistry& registry) : o_(std::move(o)), registry_(registry) {}

  bool list() {
    const auto profile = md::builtin_console_profile();
    std::string found;
    for (const md::ConnectedDevice& d : registry_.list_connected()) {
      if (d.driver == o_.driver && d.vendor_id == profile.vendor_id &&
          d.product_id == profile.product_id)
        found = d.driver + " " + d.path + " " + md::usb_id_string(d.vendor_id, d.product_id) +
                " profile " + d.profile + " serial '" + d.serial + "' product '" + d.product + "'";
    }
    result(name("list"), !found.empty(),
           found.empty() ? "no " + o_.driver + " device with the console's VID:PID listed" : found);
    return !found.empty();
  }

  bool open() {
    YAML::Node settings(YAML::NodeType::Map);
    if (o_.stale_timeout_ms > 0) settings["stale_timeout_ms"] = o_.stale_timeout_ms;
    // The loop's own ticks run tens of ms late in a loaded emulated guest;
    // the command timeout (unit-tested) must not zero the torque the
    // watchdog phase needs flowing when the host stops.
    settings["command_timeout_ms"] = 500;
    for (const auto& [key, value] : o_.settings)
      settings[key] = YAML::Load(value);
    try {
      device_ = registry_.create(o_.driver, settings);
      console_ = dynamic_cast<md::ConsoleDevice*>(device_.get());
      const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
      device_->open();
      result(name("open"), console_ != nullptr,
             fmt("%s opened in %.1f ms (DEVICE_INFO read, CALIBRATION written and read back)",
                 console_ ? console_->connected_path().c_str() : "?",
                 ms(tsmh::realtime::monotonic_now_ns() - t0)));
      return console_ != nullptr;
    } catch (const std::exception& e) {
      result(name("open"), false, e.what());
      return false;
    }
  }

  bool stream() {
    const md::ConsoleStats before = console_->stats();
    device_->set_enabled(true);
    LoopClock clock(kPeriodNs);
    // Wall time, not a tick count: a loaded guest runs fewer, later ticks.
    // A starved guest delivers most reports later than the driver's
    // freshness bound, and the driver rightly sends no torque for them: the
    // stream then goes on (up to 10 s more) until torque has flowed on
    // kTorqueTicks ticks, so that the judged torque path is exercised.
    constexpr int kTorqueTicks = 20;
    const std::int64_t t_start = tsmh::realtime::monotonic_now_ns();
    const std::int64_t t_end = t_start + static_cast<std::int64_t>(o_.seconds * 1e9);
    const std::int64_t t_limit = t_end + 10'000'000'000LL;
    std::vector<double> lateness_us, age_us;
    lateness_us.reserve(static_cast<std::size_t>(o_.seconds * 1000.0) + 1);
    age_us.reserve(static_cast<std::size_t>(o_.seconds * 1000.0) + 1);
    int ticks = 0, not_ok = 0, stale = 0, fresh = 0, enabled = 0, torque_seen = 0;
    std::uint64_t last_seq = 0;
    std::int64_t now = clock.wait();
    for (; now < t_end || (torque_seen < kTorqueTicks && now < t_limit);
         now = clock.wait(), ++ticks) {
      lateness_us.push_back(static_cast<double>(clock.lateness_ns()) * 1e-3);
      const md::DeviceReading r = device_->read(now);
      device_->write_torque(render(now, r));
      if (r.status != md::DeviceStatus::kOk) ++not_ok;
      if (r.stale) ++stale;
      if (r.fresh && r.sequence != last_seq) {
        ++fresh;
        last_seq = r.sequence;
        age_us.push_back(static_cast<double>(now - r.t_ns) * 1e-3);
      }
      if (r.enabled) ++enabled;
      if (r.tau_commanded[0] != 0.0 || r.tau_commanded[1] != 0.0) ++torque_seen;
    }
    const md::ConsoleStats s = console_->stats();
    const double seconds = static_cast<double>(now - t_start) * 1e-9;
    const auto late = tsmh::realtime::percentiles(lateness_us);
    const auto age = tsmh::realtime::percentiles(age_us);
    const auto d = [](std::uint64_t a, std::uint64_t b) {
      return static_cast<unsigned long long>(a - b);
    };
    const bool ok = s.disconnects == before.disconnects && s.bad_reports == before.bad_reports &&
                    s.outputs_failed == before.outputs_failed && enabled > 0 && torque_seen > 0 &&
                    s.reports > before.reports;
    const std::string status(md::to_string(device_->status()));
    const std::string error = device_->last_error();
    result(
        name("stream"), ok && device_->status() == md::DeviceStatus::kOk,
        fmt("%.1f s, %d ticks: %d fresh samples, input reports %llu, lost (sequence gaps) %llu, "
            "late "
            "(beyond the %.1f ms freshness bound) %llu, malformed %llu; outputs sent %llu, failed "
            "%llu; disconnects %llu; ticks not OK %d (stale %d), enabled %d, torque sent %d; now "
            "%s%s%s",
            seconds, ticks, fresh, d(s.reports, before.reports),
            d(s.lost_reports, before.lost_reports), ms(console_->freshness_bound_ns()),
            d(s.late_reports, before.late_reports), d(s.bad_reports, before.bad_reports),
            d(s.outputs_sent, before.outputs_sent), d(s.outputs_failed, before.outputs_failed),
            d(s.disconnects, before.disconnects), not_ok, stale, enabled, torque_seen,
            status.c_str(), error.empty() ? "" : ": ", error.c_str()));
    metric(name("input_reports_per_s"), static_cast<double>(s.reports - before.reports) / seconds,
           "Hz");
    metric(name("lost_reports"), static_cast<double>(s.lost_reports - before.lost_reports),
           "reports");
    metric(name("loop_ticks_per_s"), ticks / seconds, "Hz");
    metric(name("stream_seconds"), seconds, "s");
    metric(name("fresh_ratio"), ticks > 0 ? static_cast<double>(fresh) / ticks : 0.0, "of ticks");
    metric(name("ticks_not_ok"), not_ok, "ticks");
    metric(name("ticks_stale"), stale, "ticks");
    metric(name("late_reports"), static_cast<double>(s.late_reports - before.late_reports),
           "reports");
    metric(name("lateness_p50"), late.p50, "us");
    metric(name("lateness_p99"), late.p99, "us");
    metric(name("lateness_max"), late.max, "us");
    metric(name("sample_age_p50"), age.p50, "us");
    metric(name("sample_age_p99"), age.p99, "us");
    metric(name("sample_age_max"), age.max, "us");
    return ok;
  }

  // The case script sees us stopped, asks the firmware for its watchdog
  // verdict, and continues us.
  bool watchdog() {
    device_->set_enabled(true);
    LoopClock clock(kPeriodNs);
    // Torque flowing before the host "dies": the rendered spring first,
    // then a small constant hold torque (50 mA; a spring near its rest point
    // may round to 0 mA) until the driver's newest output report carries it,
    // so the watchdog has a current to cut.
    for (int k = 0; k < 300; ++k) {
      const std::int64_t now = clock.wait();
      device_->write_torque(render(now, device_->read(now)));
    }
    md::JointArray hold{};
    for (int attempt = 1;; ++attempt) {
      // A small constant hold torque, pushing joint 1 off its rest and back
      // each attempt, until the handle moves the way it pushes: proof that
      // the device applies it, not just that the driver sent it (the usb
      // driver drops superseded outputs, and a loaded guest delays the OUT
      // pipe).
      const double sign = attempt % 2 == 1 ? 1.0 : -1.0;
      hold[0] = 0.005 * sign;
      hold[1] = -0.005 * sign;
      for (int k = 0;; ++k) {
        const std::int64_t now = clock.wait();
        const md::DeviceReading r = device_->read(now);
        device_->write_torque(hold);
        if (r.enabled && r.tau_commanded[0] * sign > 0.0 && r.tau_commanded[1] * sign < 0.0 &&
            r.qd[0] * sign > 0.3 && r.qd[1] * sign < -0.3)
          break;
        if (k > 5000) {
          result(name("watchdog_resume"), false, "the hold torque never reached the device");
          return false;
        }
      }
      std::printf("HOST_STOPPING attempt %d\n", attempt);
      std::fflush(stdout);
      ::raise(SIGSTOP);
      // Continued. The firmware has judged its trip, or asks for another
      // attempt: our last output carried no current (the driver answered a
      // late report with zero torque just before the stop).
      if (attempt >= 5 || watchdog_verdict() != "retry") break;
      clock.rebase();
    }
    // Continued: the driver must be back to OK with fresh samples (stale
    // samples from the stop are not OK), torque enabled again when asked.
    const std::int64_t t0 = tsmh::realtime::monotonic_now_ns();
    clock.rebase();
    std::int64_t ok_at = 0, enabled_at = 0;
    for (int k = 0; k < 2000 && enabled_at == 0; ++k) {
      const std::int64_t now = clock.wait();
      const md::DeviceReading r = device_->read(now);
      if (r.status == md::DeviceStatus::kOk && ok_at == 0) ok_at = now;
      if (r.status == md::DeviceStatus::kOk && r.enabled) enabled_at = now;
      device_->write_torque(render(now, r));
    }
    result(name("watchdog_resume"), enabled_at != 0,
           enabled_at != 0 ? fmt("after the stop: OK in %.1f ms, torque enabled again in %.1f ms",
                                 ms(ok_at - t0), ms(enabled_at - t0))
                           : fmt("not back to OK with torque within 2000 ticks (OK: %s)",
                                 ok_at ? "yes" : "no"));
    return enabled_at != 0;
  }

  bool unplug(int round) {
    const std::string tag = fmt("unplug%d", round);
    const std::string sysfs = sysfs_of(console_->connected_path());
    if (!exists(sysfs)) {
      result(name(tag), false, "no sysfs entry for " + console_->connected_path());
      return false;
    }
    device_->set_enabled(true);
    LoopClock clock(kPeriodNs);
    for (int k = 0; k < 200; ++k) {  // settle with torque flowing
      const std::int64_t now = clock.wait();
      device_->write_torque(render(now, device_->read(now)));
    }
    // Judged against the device's last input report (when the firmware's IN
    // write completed, from the mailbox: not the driver's own dating). From
    // one loop cycle after the driver's freshness bound has passed since
    // then, read() must say "not OK, zero torque, disabled" at every tick;
    // whenever it is not OK it must say zero torque; the driver's own link
    // state (status(), no staleness in it) must flip, which starts its
    // reconnection, and read() is never OK after that. Reported: when the
    // loop saw it, relative to the last report and to the bound; when the
    // kernel hung up the device node (our own fd on it) and when the
    // driver's link-loss path fired, i.e. what the kernel and the library
    // take, and why.
    const UnplugWatch watch(console_->connected_path());
    if (!watch.valid()) {
      result(name(tag), false, "cannot open the device node of " + console_->connected_path());
      return false;
    }
    const MailboxMap mailbox(o_.mailbox, false);
    if (!mailbox.valid()) {
      result(name(tag), false, "cannot map the firmware's mailbox " + o_.mailbox);
      return false;
    }
    constexpr int kMaxTicks = 5000;
    std::vector<std::int64_t> tick_ns(kMaxTicks);
    std::vector<char> tick_ok(kMaxTicks);
    int ticks = 0, hup_tick = -1, link_tick = -1, torque_leaks = 0, ok_after_link = 0;
    std::int64_t newest_sample_ns = 0;
    const std::int64_t bound_ns = console_->freshness_bound_ns();
    const md::ConsoleStats before = console_->stats();
    const std::int64_t t_start = tsmh::realtime::monotonic_now_ns();
    std::int64_t hup_ns = 0, gone_ns = 0, link_ns = 0;
    std::string link_why;
    {
      UdcWriter unbind(o_.udc_file, "");
      // Until the kernel, the driver and the unbind are all done, and the
      // loop has ticked past the bound + one cycle after the last report.
      const auto done = [&](std::int64_t now) {
        return hup_tick >= 0 && gone_ns != 0 && link_tick >= 0 && unbind.done_ns() != 0 &&
               now > mailbox->last_in_ns.load() + bound_ns + 2 * kPeriodNs;
      };
      for (std::int64_t now = 0; ticks < kMaxTicks && !done(now); ++ticks) {
        now = clock.wait();
        // The kernel first, then the driver: the same tick counts as in time.
        if (hup_tick < 0 && watch.hung_up()) {
          hup_tick = ticks;
          hup_ns = tsmh::realtime::monotonic_now_ns();
        }
        if (gone_ns == 0 && !exists(sysfs)) gone_ns = tsmh::realtime::monotonic_now_ns();
        const md::DeviceReading r = device_->read(now);
        tick_ns[static_cast<std::size_t>(ticks)] = now;
        tick_ok[static_cast<std::size_t>(ticks)] = r.status == md::DeviceStatus::kOk;
        newest_sample_ns = std::max(newest_sample_ns, r.t_ns);
        if (r.status != md::DeviceStatus::kOk) {
          if (r.enabled || std::any_of(r.tau_commanded.begin(), r.tau_commanded.end(),
                                       [](double t) { return t != 0.0; }))
            ++torque_leaks;
        } else if (link_tick >= 0) {
          ++ok_after_link;  // the driver knew a cycle ago
        }
        if (link_tick < 0 && device_->status() != md::DeviceStatus::kOk) {
          link_tick = ticks;
          link_ns = tsmh::realtime::monotonic_now_ns();
          link_why = device_->last_error();
        }
        device_->write_torque(render(now, r));  // the loop keeps asking for torque
      }
      if (!unbind.ok()) {
        result(name(tag), false, "writing '' to " + o_.udc_file + " failed");
        return false;
      }
    }
    const md::ConsoleStats after = console_->stats();
    const std::int64_t last_ns = mailbox->last_in_ns.load();
    const std::int64_t gadget_lost_ns = mailbox->link_lost_ns.load();
    // The guarantee: not OK from one cycle past the bound after the last report.
    const std::int64_t deadline_ns = last_ns + bound_ns + kPeriodNs;
    int ok_past_deadline = 0, ok_past_bound = 0;
    int detect = -1;      // first tick of the final run of not-OK ticks
    int first_past = -1;  // first loop tick past the bound
    for (int k = 0; k < ticks; ++k) {
      const auto i = static_cast<std::size_t>(k);
      if (tick_ok[i] && tick_ns[i] > deadline_ns) ++ok_past_deadline;
      if (tick_ok[i] && tick_ns[i] > last_ns + bound_ns) ++ok_past_bound;
      if (first_past < 0 && tick_ns[i] > last_ns + bound_ns) first_past = k;
      if (tick_ok[i]) detect = -1;
      if (!tick_ok[i] && detect < 0) detect = k;
    }
    const std::int64_t detect_ns = detect >= 0 ? tick_ns[static_cast<std::size_t>(detect)] : 0;
    const std::int64_t first_past_ns =
        first_past >= 0 ? tick_ns[static_cast<std::size_t>(first_past)] : 0;
    const bool ok = last_ns > 0 && hup_tick >= 0 && link_tick >= 0 && detect >= 0 &&
                    ok_past_deadline == 0 && torque_leaks == 0 && ok_after_link == 0;
    const auto since_last = [&](std::int64_t t) { return t != 0 ? ms(t - last_ns) : -1.0; };
    result(
        name(tag), ok,
        fmt("the device's last input report left %.1f ms after the unbind started; read() not OK "
            "(torque %s) from %+.2f ms after it: freshness bound %.1f ms, OK at %d loop ticks past "
            "the bound (allowed: within one cycle; past that: %d), first tick past it at %+.2f ms; "
            "the driver dated its newest sample %+.2f ms from the last report; gadget disabled "
            "%+.1f ms, kernel hung up the device node %+.1f ms, driver's link-loss path %+.1f ms "
            "(%s), OK after that %d times; sysfs entry gone %+.1f ms; malformed reports %llu",
            last_ns > 0 ? ms(last_ns - t_start) : -1.0, torque_leaks == 0 ? "zero" : "NOT zero",
            since_last(detect_ns), ms(bound_ns), ok_past_bound, ok_past_deadline,
            since_last(first_past_ns), ms(newest_sample_ns - last_ns), since_last(gadget_lost_ns),
            since_last(hup_ns), since_last(link_ns), link_why.c_str(), ok_after_link,
            since_last(gone_ns),
            static_cast<unsigned long long>(after.bad_reports - before.bad_reports)));
    metric(name(tag + "_not_ok_after_last_report"), since_last(detect_ns), "ms");
    metric(name(tag + "_ok_ticks_past_bound"), ok_past_bound, "ticks");
    metric(name(tag + "_first_tick_past_bound"), since_last(first_past_ns), "ms");
    metric(name(tag + "_hangup_after_last_report"), since_last(hup_ns), "ms");
    metric(name(tag + "_link_loss_after_last_report"), since_last(link_ns), "ms");
    metric(name(tag + "_link_loss_after_hangup"), ms(link_ns - hup_ns), "ms");

    // Rebind: the supervisor must find the device again by itself.
    const std::int64_t t_bind = tsmh::realtime::monotonic_now_ns();
    std::int64_t ok_at = 0;
    int enabled_while_not_asked = 0;
    {
      UdcWriter bind(o_.udc_file, o_.udc_name);
      clock.rebase();
      for (int k = 0; k < 10000 && ok_at == 0; ++k) {
        const std::int64_t now = clock.wait();
        const md::DeviceReading r = device_->read(now);
        if (r.status == md::DeviceStatus::kOk && r.fresh) {
          ok_at = now;
          if (r.enabled) ++enabled_while_not_asked;
        }
        device_->write_torque(render(now, r));
      }
    }
    // Back, but disabled until the loop asks again: check a few more ticks.
    for (int k = 0; k < 100 && ok_at != 0; ++k) {
      const std::int64_t now = clock.wait();
      const md::DeviceReading r = device_->read(now);
      if (r.enabled) ++enabled_while_not_asked;
      device_->write_torque(render(now, r));
    }
    const std::string path = console_->connected_path();
    result(name(tag + "_rebind"), ok_at != 0 && enabled_while_not_asked == 0,
           ok_at != 0 ? fmt("back as %s %.1f ms after the bind started, %s", path.c_str(),
                            ms(ok_at - t_bind),
                            enabled_while_not_asked == 0 ? "torque disabled until re-enabled"
                                                         : "torque ENABLED without being asked")
                      : std::string("not back within 10 s: ") + device_->last_error());
    metric(name(tag + "_rebind_ms"), ok_at != 0 ? ms(ok_at - t_bind) : -1.0, "ms");
    return ok_at != 0;
  }

  void close() {
    if (device_) device_->close();
  }

 private:
  std::string name(const std::string& phase) const { return o_.prefix + "_" + phase; }
  std::string watchdog_verdict() const {
    std::string v;
    std::ifstream(o_.mailbox + ".watchdog") >> v;
    return v;
  }
  // A soft virtual spring-damper the handle follows (joint 0 tracks a slow
  // sine, joint 1 is pushed off centre by a constant bias), as a haptic
  // loop renders: motor current flows all the time, and the handle stays
  // inside its workspace only if the driver's angle and torque signs agree.
  // Without a reading the previous command is repeated: the driver, not
  // the loop, must zero the torque when the device goes away.
  md::JointArray render(std::int64_t now, const md::DeviceReading& r) {
    if (r.status != md::DeviceStatus::kOk || r.sequence == 0) return last_tau_;
    // Soft enough (1.1 Hz with the handle's inertia, overdamped by its own
    // friction) to stay stable with the tens of ms of delay an emulated,
    // loaded guest adds.
    constexpr double kStiffness = 0.01;  // N m / rad
    const double t = static_cast<double>(now) * 1e-9;
    const std::array<double, 2> ref{0.2 * std::sin(2.0 * 3.14159265 * 0.5 * t), 0.0};
    const std::array<double, 2> bias{0.0, o_.torque_nm * 0.2};
    for (std::size_t j = 0; j < 2 && j < r.dof; ++j) {
      last_tau_[j] =
          std::clamp(-kStiffness * (r.q[j] - ref[j]) + bias[j], -o_.torque_nm, o_.torque_nm);
    }
    return last_tau_;
  }

  Options o_;
  md::DriverRegistry& registry_;
  std::unique_ptr<md::Device> device_;
  md::ConsoleDevice* console_ = nullptr;
  md::JointArray last_tau_{};
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string flag = argv[i];
    const bool has_value = i + 1 < argc;
    if (flag == "--no-watchdog") {
      o.watchdog = false;
    } else if (flag == "--driver" && has_value) {
      o.driver = argv[++i];
    } else if (flag == "--prefix" && has_value) {
      o.prefix = argv[++i];
    } else if (flag == "--udc" && has_value) {
      o.udc_file = argv[++i];
    } else if (flag == "--set" && has_value &&
               std::string(argv[i + 1]).find('=') != std::string::npos) {
      const std::string kv = argv[++i];
      o.settings.emplace_back(kv.substr(0, kv.find('=')), kv.substr(kv.find('=') + 1));
    } else if (flag == "--mailbox" && has_value) {
      o.mailbox = argv[++i];
    } else if (flag == "--udc-name" && has_value) {
      o.udc_name = argv[++i];
    } else if (flag == "--seconds" && has_value) {
      o.seconds = std::atof(argv[++i]);
    } else if (flag == "--replugs" && has_value) {
      o.replugs = std::atoi(argv[++i]);
    } else if (flag == "--stale-timeout-ms" && has_value) {
      o.stale_timeout_ms = std::atol(argv[++i]);
    } else {
      std::fprintf(stderr, "console_host: bad argument %s\n", flag.c_str());
      return 2;
    }
  }
  if (o.prefix.empty()) o.prefix = o.driver;
  if (o.udc_file.empty() || o.mailbox.empty()) {
    std::fprintf(stderr, "console_host: --udc FILE and --mailbox FILE are required\n");
    return 2;
  }

  md::DriverRegistry registry;
  md::register_builtin_drivers(registry);
  Host host(o, registry);
  const auto phase = [&](const char* what) {
    std::printf("USB_STACK_PHASE %s_%s t=%.3f\n", o.prefix.c_str(), what,
                ms(tsmh::realtime::monotonic_now_ns()) * 1e-3);
    std::fflush(stdout);
  };
  phase("list");
  host.list();
  phase("open");
  if (!host.open()) return 1;
  phase("stream");
  host.stream();
  phase("watchdog");
  if (o.watchdog) host.watchdog();
  for (int k = 1; k <= o.replugs; ++k) {
    phase("unplug");
    if (!host.unplug(k)) break;
  }
  phase("close");
  host.close();
  phase("end");
  return 0;
}
