#include "master_devices/sim_device.hpp"

#include <time.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "master_devices/clock.hpp"
#include "realtime/clock.hpp"
#include "realtime/pacing.hpp"

namespace tsmh::master_devices {
SimSettings parse_sim_settings(config::FieldReader& r) {
  SimSettings s;
  const std::string time = r.get_string("time", "real");
  if (time != "real" && time != "simulated") r.fail("time", "must be 'real' or 'simulated'");
  s.simulated_time = time == "simulated";
  s.rate_hz = r.get_positive("rate_hz", s.rate_hz);
  const long long dof = r.get_int("dof", 2);
  if (dof < 1 || dof > static_cast<long long>(kMaxDof)) {
    r.fail("dof", "must be 1 .. " + std::to_string(kMaxDof));
  }
  s.dof = static_cast<std::size_t>(dof);
  s.scenario = parse_scenario(r, s.dof);

  config::FieldReader hand(r.node("hand"), r.source(), r.field("hand"));
  s.hand.inertia_kgm2 = hand.get_positive("inertia_kgm2", s.hand.inertia_kgm2);
  s.hand.stiffness_nm_per_rad =
      hand.get_positive("stiffness_nm_per_rad", s.hand.stiffness_nm_per_rad);
  s.hand.damping_nms_per_rad = hand.get_double("damping_nms_per_rad", s.hand.damping_nms_per_rad);
  if (s.hand.damping_nms_per_rad < 0) hand.fail("damping_nms_per_rad", "must be >= 0");
  hand.reject_unknown();
  config::FieldReader handle(r.node("handle"), r.source(), r.field("handle"));
  s.handle.inertia_kgm2 = handle.get_positive("inertia_kgm2", s.handle.inertia_kgm2);
  s.handle.damping_nms_per_rad =
      handle.get_double("damping_nms_per_rad", s.handle.damping_nms_per_rad);
  if (s.handle.damping_nms_per_rad < 0) handle.fail("damping_nms_per_rad", "must be >= 0");
  handle.reject_unknown();

  r.get_joint_array("peak_torque_nm", s.peak_torque_nm, s.dof);
  r.get_joint_array("continuous_torque_nm", s.continuous_torque_nm, s.dof);
  r.get_joint_array("position_min_rad", s.position_min_rad, s.dof);
  r.get_joint_array("position_max_rad", s.position_max_rad, s.dof);
  r.get_joint_array("max_stiffness_nm_per_rad", s.max_stiffness_nm_per_rad, s.dof);
  for (std::size_t j = 0; j < s.dof; ++j) {
    if (!(s.peak_torque_nm[j] > 0.0)) r.fail("peak_torque_nm", "must be > 0");
    if (!(s.continuous_torque_nm[j] > 0.0 && s.continuous_torque_nm[j] <= s.peak_torque_nm[j])) {
      r.fail("continuous_torque_nm", "must be > 0 and <= peak_torque_nm");
    }
    if (!(s.position_min_rad[j] < s.position_max_rad[j])) {
      r.fail("position_max_rad", "must be > position_min_rad");
    }
  }
  s.encoder_resolution_rad = r.get_double("encoder_resolution_rad", 0.0);
  if (s.encoder_resolution_rad < 0) r.fail("encoder_resolution_rad", "must be >= 0");
  s.command_timeout_ms = r.get_int("command_timeout_ms", s.command_timeout_ms);
  if (s.command_timeout_ms < 1) r.fail("command_timeout_ms", "must be >= 1");
  s.stale_timeout_ms = r.get_int("stale_timeout_ms", s.stale_timeout_ms);
  if (s.stale_timeout_ms < 1) r.fail("stale_timeout_ms", "must be >= 1");
  s.buttons.dead_man = r.get_bool("dead_man", true);
  s.buttons.clutch = r.get_bool("clutch", false);
  s.buttons.e_stop = r.get_bool("e_stop", false);
  return s;
}

SimDevice::SimDevice(SimSettings settings, std::shared_ptr<const Clock> clock)
    : DriverBase(std::move(clock)),
      settings_(std::move(settings)),
      operator_(settings_.scenario, settings_.dof, settings_.hand, settings_.handle) {
  spec_.model = "sim-" + std::string(scenario_name(settings_.scenario));
  spec_.driver = "sim";
  spec_.dof = static_cast<std::uint32_t>(settings_.dof);
  spec_.nominal_rate_hz = settings_.rate_hz;
  copy_joint_limits(settings_, spec_);
  for (std::size_t j = 0; j < settings_.dof; ++j)
    spec_.encoder_resolution_rad[j] = settings_.encoder_resolution_rad;
}

SimDevice::~SimDevice() {
  close();
}

void SimDevice::open() {
  if (opened_) return;
  operator_.reset();
  count_ = 0;
  started_ = false;
  set_enabled(false);
  link_up_ = true;  // a simulated hand never goes away
  opened_ = true;
  if (!settings_.simulated_time) {
    stopping_ = false;
    advance(0.0, clock_->now_ns());  // a first reading at once
    thread_ = std::thread([this] { run_real_time(); });
  }
}

void SimDevice::close() noexcept {
  if (!opened_.exchange(false)) return;
  stopping_ = true;
  if (thread_.joinable()) thread_.join();
}

void SimDevice::advance(double dt_s, std::int64_t t_ns) noexcept {
  Command cmd;
  command_reader_.fetch(cmd);
  // In simulated time a command holds until the next: the loop and the world
  // advance together, so no command can be late.
  const Torque torque =
      torque_to_send(cmd, t_ns,
                     settings_.simulated_time ? std::numeric_limits<std::int64_t>::max()
                                              : settings_.command_timeout_ms * 1'000'000LL);
  operator_.step(dt_s, torque.tau);
  scenario_t_ = operator_.time_s();

  DeviceReading r;
  r.t_ns = t_ns;
  r.sequence = ++count_;
  r.dof = static_cast<std::uint32_t>(settings_.dof);
  for (std::size_t j = 0; j < settings_.dof; ++j) {
    const double q = operator_.q()[j];
    const double res = settings_.encoder_resolution_rad;
    r.q[j] = res > 0.0 ? res * std::floor(q / res + 0.5) : q;
    r.qd[j] = operator_.qd()[j];
  }
  r.tau_commanded = torque.tau;
  r.buttons = settings_.buttons;
  // The scenario's own button presses (the recalibration button of the
  // palpate scenario's sweep).
  if (intention_at(settings_.scenario, operator_.time_s(), settings_.dof).calibrate)
    r.buttons.calibrate = true;
  r.enabled = true;  // the host's request decides (apply_reading_rules)
  r.status = DeviceStatus::kOk;
  readings_.store(r);
}

void SimDevice::run_real_time() {
  const std::int64_t period_ns = static_cast<std::int64_t>(1e9 / settings_.rate_hz);
  // Paced on CLOCK_MONOTONIC (a thread sleeps in real time), stamped on
  // clock_. After a stall the schedule skips the missed periods, and the
  // next step covers them: the simulated operator stays on real time.
  realtime::Pacer pace(period_ns, realtime::monotonic_now_ns() + period_ns);
  std::int64_t periods = 1;
  while (!stopping_) {
    pace.wait_through_signals();
    advance(static_cast<double>(periods * period_ns) * 1e-9, clock_->now_ns());
    periods = 1 + pace.advance(realtime::monotonic_now_ns());
  }
}

DeviceReading SimDevice::read(std::int64_t now_ns) noexcept {
  if (settings_.simulated_time && opened_) {
    if (!started_) {
      started_ = true;
      last_t_ns_ = now_ns;
      advance(0.0, now_ns);
    } else if (now_ns > last_t_ns_) {
      advance(static_cast<double>(now_ns - last_t_ns_) * 1e-9, now_ns);
      last_t_ns_ = now_ns;
    }
  }
  return DriverBase::read(now_ns);
}

std::int64_t SimDevice::freshness_bound_ns() const noexcept {
  return settings_.simulated_time ? std::numeric_limits<std::int64_t>::max()
                                  : settings_.stale_timeout_ms * 1'000'000LL;
}

}  // namespace tsmh::master_devices
