#include "haptics/haptic_loop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "realtime/enum_names.hpp"

namespace tsmh::haptics {

std::string_view to_string(FeedbackSource s) noexcept {
  return realtime::enum_name<FeedbackSource::kNone>(s, {"estimated", "naive", "none"});
}

namespace {

// The recalibration worker's own copies of the joints' models (allocated
// here, at construction, never in the loop); none for a model that is only
// a FrictionDynamics.
std::vector<std::unique_ptr<estimator::FrictionModel>> model_replicas(
    const std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>>& estimators) {
  std::vector<std::unique_ptr<estimator::FrictionModel>> out;
  for (const auto& e : estimators) {
    const auto* m = e ? dynamic_cast<const estimator::FrictionModel*>(&e->model()) : nullptr;
    out.push_back(m ? m->clone() : nullptr);
  }
  return out;
}

}  // namespace

HapticLoop::HapticLoop(const LoopConfig& config, master_devices::Device& device, SlaveLink& link,
                       std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> estimators,
                       TraceSink* trace)
    : config_(config),
      device_(device),
      link_(link),
      estimators_(std::move(estimators)),
      trace_(trace),
      calibration_(config.joints, config.recalibration, config.drift, model_replicas(estimators_)),
      safety_(config.joints, config.limits, config.timing),
      oscillation_(config.joints, config.oscillation, config.rate_hz) {
  for (auto& t : truths_)
    t.seq = -1;
  if (static_cast<int>(estimators_.size()) != config_.joints)
    throw std::invalid_argument("haptic loop: one estimator per joint is needed");
  for (const auto& e : estimators_)
    if (!e) throw std::invalid_argument("haptic loop: missing estimator");
  if (!(config_.rate_hz >= LoopConfig::kMinRateHz && config_.rate_hz <= LoopConfig::kMaxRateHz)) {
    char what[64];
    std::snprintf(what, sizeof what, "rate_hz: must be within %g..%g", LoopConfig::kMinRateHz,
                  LoopConfig::kMaxRateHz);
    throw std::invalid_argument(what);
  }
  if (config_.status_every < 1) throw std::invalid_argument("status_every: must be >= 1");
  if (trace_ && trace_->joints() != config_.joints)
    throw std::invalid_argument("haptic loop: trace joint count differs");
  for (int j = 0; j < config_.joints; ++j) {
    const auto i = static_cast<std::size_t>(j);
    position_[i] = PositionMapping(config_.position[i]);
    passivity_[i] = PassivityChannel(config_.passivity);
  }
}

double HapticLoop::measured_rate_hz() const noexcept {
  if (counters_.ticks < 2 || last_ns_ <= first_ns_) return 0.0;
  return static_cast<double>(counters_.ticks - 1) /
         (static_cast<double>(last_ns_ - first_ns_) * 1e-9);
}

// One tick, as the numbered pipeline of docs/architecture.md ("A tick").
// Each step records what it decided in facts_; status and trace publish
// from there.
void HapticLoop::tick(std::int64_t now_ns, std::int64_t lateness_ns) noexcept {
  if (shut_down_) return;
  TickFacts& f = facts_;
  begin_tick(now_ns, lateness_ns, f);  // 0. time and lateness
  reading_ = device_.read(now_ns);     // 1. the master
  recalibrate(f);                      // 1b. recalibration requests, results, scale ramp
  take_slave_state(f);                 // 2. newest SLAVE_STATE -> estimators
  track_estimate_loss(f);              // 3. invalid estimates held and timed
  request_feedback(f);                 // 4. force mapping per joint
  decide_state(f);                     // 5. device freshness, state machine, enable
  render(f);                           // 6. shaping, safety, the device
  command_slave(f);                    // 7. MASTER_COMMAND (position mapping, clutch)
  if (counters_.ticks % static_cast<std::uint64_t>(config_.status_every) == 0 || f.fault_entered())
    publish_status(f);          // 8. HAPTIC_STATUS at 100 Hz, and at once on a fault
  if (trace_) append_trace(f);  // 9. trace (evaluation, plots)
}

void HapticLoop::begin_tick(std::int64_t now_ns, std::int64_t lateness_ns, TickFacts& f) noexcept {
  const double nominal_dt = 1.0 / config_.rate_hz;
  f.now_ns = now_ns;
  f.lateness_ns = lateness_ns;
  f.dt = counters_.ticks == 0 ? nominal_dt : static_cast<double>(now_ns - last_ns_) * 1e-9;
  if (counters_.ticks == 0) first_ns_ = now_ns;
  last_ns_ = now_ns;
  ++counters_.ticks;
  lateness_.record(lateness_ns);
  window_lateness_.record(lateness_ns);
  if (lateness_ns > events_.worst_lateness_ns.load(std::memory_order_relaxed))
    events_.worst_lateness_ns.store(lateness_ns, std::memory_order_relaxed);
}

// Recalibration (recalibration.hpp): a request from the master's button or an
// external console's CALIBRATION_REQUEST, the end of a collection, the
// worker's result, and the applied friction scale's ramp. Never waits.
void HapticLoop::recalibrate(const TickFacts& f) noexcept {
  const std::uint64_t v = link_.latest_calibration_request(calibration_request_);
  if (v != 0 && v != calibration_request_version_) {
    calibration_request_version_ = v;
    std::uint32_t mask = 0;
    for (int j = 0; j < config_.joints && j < calibration_request_.num_joints; ++j)
      if (calibration_request_.recalibrate[static_cast<std::size_t>(j)]) mask |= 1U << j;
    calibration_.request(mask);
  }
  calibration_.on_tick(static_cast<double>(f.now_ns - first_ns_) * 1e-9, f.dt,
                       reading_.buttons.calibrate);
}

// The estimator runs once per new sample, on the slave's own clock (utime),
// so its differentiator sees true intervals.
void HapticLoop::take_slave_state(TickFacts& f) noexcept {
  // The truth is read right before and right after the state (evaluation
  // only): SLAVE_TRUTH N arrives before SLAVE_STATE N, so one of the two
  // reads sees the state's own truth unless two whole pairs land within
  // these few instructions. A single read at the end of the tick lost it
  // whenever the next pair arrived during the tick's device I/O.
  collect_truth();
  const std::uint64_t version = link_.latest_state(state_);
  collect_truth();
  if (version != 0 && version != state_version_) {
    state_version_ = version;
    ++counters_.slave_samples;
    events_.slave_samples.store(counters_.slave_samples, std::memory_order_relaxed);
    estimate();
  }
  f.slave_age_s = have_state_ ? static_cast<double>(f.now_ns - state_.receive_ns) * 1e-9
                              : std::numeric_limits<double>::infinity();
}

// Loss of the estimate: the last valid estimate is held and faded exactly
// like a stale slave (the fade counts from the loss), and the loop faults if
// it lasts estimate_fault_s. The flag goes out in HAPTIC_STATUS and the
// server logs it from its main thread.
void HapticLoop::track_estimate_loss(TickFacts& f) noexcept {
  std::uint32_t lost = 0;
  if (have_state_ && config_.source != FeedbackSource::kNone)
    for (std::size_t j = 0; j < static_cast<std::size_t>(config_.joints); ++j)
      if (!estimates_[j].valid) lost |= 1U << j;
  if (lost != 0) {
    if (estimate_lost_since_ns_ < 0) estimate_lost_since_ns_ = f.now_ns;
    ++counters_.estimate_lost_ticks;
  } else {
    estimate_lost_since_ns_ = -1;
  }
  f.lost_joints = lost;
  f.lost_s = lost != 0 ? static_cast<double>(f.now_ns - estimate_lost_since_ns_) * 1e-9 : 0.0;
  events_.estimate_lost_joints.store(lost, std::memory_order_relaxed);
}

// NaN passes through: the safety filter zeroes it.
void HapticLoop::request_feedback(TickFacts& f) noexcept {
  f.request = {};
  for (std::size_t j = 0; j < static_cast<std::size_t>(config_.joints); ++j)
    f.request[j] = config_.force[j](slave_torque(j));
}

// The driver decides whether its reading is fresh; a late one (stale, link
// up) zeroes torque this tick (render) and becomes a fault only if it lasts
// device_stale_fault_s.
void HapticLoop::decide_state(TickFacts& f) noexcept {
  f.device_fresh = reading_.status == master_devices::DeviceStatus::kOk;
  const bool device_late =
      reading_.status == master_devices::DeviceStatus::kDisconnected && reading_.stale;
  if (device_late) {
    if (device_stale_since_ns_ < 0) device_stale_since_ns_ = f.now_ns;
    ++counters_.device_stale_ticks;
  } else {
    device_stale_since_ns_ = -1;
  }
  const bool device_ok =
      f.device_fresh ||
      (device_late && static_cast<double>(f.now_ns - device_stale_since_ns_) * 1e-9 <
                          config_.device_stale_fault_s);
  const double nominal_dt = 1.0 / config_.rate_hz;
  f.before = machine_.state();
  f.state = machine_.update(
      {.dead_man = reading_.buttons.dead_man,
       .e_stop = reading_.buttons.e_stop,
       .device_ok = device_ok,
       .slave_lost = !(f.slave_age_s <= config_.slave_timeout_s) &&
                     counters_.ticks * nominal_dt > config_.slave_timeout_s,
       .estimate_lost = f.lost_s > config_.estimate_fault_s,
       .slave_session_over = link_.session_over(),
       .master_session_over = reading_.fault == master_devices::FaultCode::kOtherSession});
  if (f.fault_entered()) {
    ++counters_.faults;
    events_.faults.store(counters_.faults, std::memory_order_relaxed);
  }
  events_.state.store(static_cast<std::int32_t>(f.state), std::memory_order_relaxed);
  events_.fault.store(static_cast<std::int32_t>(machine_.fault()), std::memory_order_relaxed);
  f.enabled = f.state == LoopState::kEnabled;
  if (f.enabled != device_enabled_) {
    device_.set_enabled(f.enabled);
    device_enabled_ = f.enabled;
  }
}

void HapticLoop::render(TickFacts& f) noexcept {
  const bool drive = f.enabled && f.device_fresh;
  shape_request(f.request, f.dt, drive);
  f.out = safety_.apply(f.request, f.dt, std::max(f.slave_age_s, f.lost_s), drive);
  observe_rendered(f.out);
  if (f.out.flags & safety_flags::kNonFinite) ++counters_.nonfinite_requests;
  if (f.out.flags & safety_flags::kSaturated) ++counters_.saturated_ticks;
  if (f.out.flags & safety_flags::kRateLimited) ++counters_.rate_limited_ticks;
  if (f.out.flags & safety_flags::kStaleFade) ++counters_.stale_ticks;
  const auto n = static_cast<std::size_t>(config_.joints);
  for (std::size_t j = 0; j < master_devices::kMaxDof; ++j)
    device_torque_[j] = j < n ? f.out.torque[j] : 0.0;
  device_.write_torque(device_torque_);
}

// The position mapping's only user: aligned on each enabling, so enabling
// never makes the slave jump, then followed.
void HapticLoop::command_slave(const TickFacts& f) noexcept {
  const auto n = static_cast<std::size_t>(config_.joints);
  if (f.enabled && f.before != LoopState::kEnabled) {
    for (std::size_t j = 0; j < n; ++j) {
      const double slave_at = std::isfinite(state_.x_out[j]) && have_state_
                                  ? state_.x_out[j]
                                  : position_[j].reference();
      position_[j].align(reading_.q[j], slave_at);
    }
  }
  command_.utime = f.now_ns / 1000;
  command_.seq = command_seq_++;
  command_.num_joints = config_.joints;
  command_.enable = f.enabled;
  command_.clutch = reading_.buttons.clutch;
  for (std::size_t j = 0; j < n; ++j)
    command_.position_ref[j] = f.enabled
                                   ? position_[j].update(reading_.q[j], reading_.buttons.clutch)
                                   : position_[j].reference();
  link_.publish_command(command_);
}

void HapticLoop::collect_truth() noexcept {
  if (!trace_) return;  // the truth only ever goes into the trace
  const std::uint64_t version = link_.latest_truth(truth_in_);
  if (version == 0 || version == truth_version_ || truth_in_.seq < 0) return;
  truth_version_ = version;
  truths_[static_cast<std::size_t>(truth_in_.seq) % truths_.size()] = truth_in_;
}

void HapticLoop::append_trace(const TickFacts& f) noexcept {
  // Empty slots hold seq -1, so a slot matches only a truth collected for this state.
  const bridge::SlaveTruthSample& truth =
      truths_[static_cast<std::size_t>(std::max<std::int64_t>(state_.seq, 0)) % truths_.size()];
  const bool truth_matches = have_state_ && state_.seq >= 0 && truth.seq == state_.seq;
  TraceRow row;
  row.t = static_cast<double>(f.now_ns - first_ns_) * 1e-9;
  row.state_seq = have_state_ ? state_.seq : -1;
  row.state = static_cast<std::int32_t>(f.state);
  row.flags = static_cast<std::int32_t>(f.out.flags);
  row.lateness_us = static_cast<double>(f.lateness_ns) * 1e-3;
  constexpr double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t j = 0; j < static_cast<std::size_t>(config_.joints); ++j) {
    auto& r = row.joints[j];
    r.master_q = reading_.q[j];
    r.slave_ref = command_.position_ref[j];
    r.tau_in = estimates_[j].tau_in;
    r.tau_out_est = estimates_[j].tau_out_est;
    r.torque_cmd = f.out.torque[j];
    r.x_in = have_state_ ? state_.x_in[j] : nan;
    r.x_out = have_state_ ? state_.x_out[j] : nan;
    r.true_tau_out = truth_matches ? truth.tau_out[j] : nan;
    r.true_x_out = truth_matches ? truth.x_out[j] : nan;
    r.indentation = truth_matches ? truth.indentation[j] : nan;
    r.contact_force = truth_matches ? truth.contact_force[j] : nan;
  }
  trace_->append(row);
}

void HapticLoop::record_compute(std::int64_t compute_ns, std::int64_t skipped) noexcept {
  compute_.record(compute_ns);
  window_compute_.record(compute_ns);
  if (skipped > 0) {
    counters_.overruns += static_cast<std::uint64_t>(skipped);
    overrun_in_period_ = true;
    events_.overruns.store(counters_.overruns, std::memory_order_relaxed);
  }
}

double HapticLoop::slave_torque(std::size_t j) const noexcept {
  // A joint without a valid estimate renders its last valid one, fading.
  const estimator::Estimate& e = estimates_[j].valid ? estimates_[j] : held_[j];
  switch (config_.source) {
    case FeedbackSource::kEstimated:
      return e.tau_out_est;
    case FeedbackSource::kNaive:
      return e.tau_in;
    case FeedbackSource::kNone:
      return 0.0;
  }
  return 0.0;
}

void HapticLoop::estimate() noexcept {
  const auto n = static_cast<std::size_t>(config_.joints);
  // A slave clock that jumps -- back (the slave rebooted) or forward by more
  // than the slave timeout -- leaves the differentiators and friction states
  // in another time base, and every later sample would be rejected as "time
  // not increasing": re-initialise them so the estimate recovers at once.
  // (Doubles: a hostile utime must not overflow the subtraction.)
  if (have_state_) {
    const double jump_s =
        (static_cast<double>(state_.utime) - static_cast<double>(last_utime_)) * 1e-6;
    if (!(jump_s > 0.0) || jump_s > config_.slave_timeout_s) {
      for (std::size_t j = 0; j < n; ++j) {
        estimators_[j]->reset();
        passivity_[j].reset();  // the slave's angles are in another time base too
      }
      ++counters_.estimator_resets;
      clock_reset_in_period_ = true;
      events_.last_reset_jump_us.store(
          static_cast<std::int64_t>(std::clamp(jump_s, -9e12, 9e12) * 1e6),
          std::memory_order_relaxed);
      events_.estimator_resets.store(counters_.estimator_resets, std::memory_order_relaxed);
    }
  }
  have_state_ = true;
  last_utime_ = state_.utime;
  const bool joints_ok = state_.num_joints >= config_.joints;
  for (std::size_t j = 0; j < n; ++j) {
    auto& e = estimates_[j];
    if (calibration_.scales_levels(static_cast<int>(j)))
      estimators_[j]->set_level_scales(calibration_.applied_scale(static_cast<int>(j), false),
                                       calibration_.applied_scale(static_cast<int>(j), true));
    e = joints_ok ? estimators_[j]->update_tensions(static_cast<double>(state_.utime) * 1e-6,
                                                    state_.x_in[j], state_.T1[j], state_.T3[j],
                                                    state_.x_out[j])
                  : estimator::Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
    if (e.valid) {
      // The recalibrated friction scale, the drift monitor, the collection.
      calibration_.on_estimate(static_cast<int>(j), static_cast<double>(state_.utime) * 1e-6,
                               state_.x_in[j], e, estimators_[j]->radius());
      held_[j] = e;
    } else {
      // Whatever made it invalid, the next sample starts the estimator afresh
      // instead of leaving it stuck.
      ++counters_.estimator_rejects;
      estimators_[j]->reset();
    }
  }
  observe_slave_ports();
}

// The calibration fields of HAPTIC_STATUS; returns its flags.
std::int32_t HapticLoop::calibration_status(bridge::HapticStatusSample& st) const noexcept {
  const CalibrationState cs = calibration_.state();
  st.calibration_state = static_cast<std::int32_t>(cs);
  st.calibration_reason = static_cast<std::int32_t>(calibration_.reason());
  st.calibration_joint = calibration_.reason_joint();
  for (int j = 0; j < config_.joints; ++j) {
    st.friction_scale[static_cast<std::size_t>(j)] = calibration_.applied_scale(j);
    st.drift_scale[static_cast<std::size_t>(j)] = calibration_.drift_scale(j);
  }
  std::int32_t flags = 0;
  if (calibration_.drift_alarms() != 0) flags |= status_flags::kDriftSuspected;
  if (cs == CalibrationState::kCollecting || cs == CalibrationState::kIdentifying)
    flags |= status_flags::kRecalibrating;
  return flags;
}

// HAPTIC_STATUS flags from what this tick decided and what happened in
// the status period (lcmtypes/haptic_status_t.lcm).
std::int32_t HapticLoop::status_flags_of(const TickFacts& f) const noexcept {
  std::int32_t flags = 0;
  if (f.out.flags & safety_flags::kStaleFade) flags |= status_flags::kStaleFade;
  if (reading_.buttons.e_stop) flags |= status_flags::kEStop;
  if (!reading_.buttons.dead_man) flags |= status_flags::kDeadManReleased;
  if (f.out.flags & safety_flags::kSaturated) flags |= status_flags::kSaturated;
  if (f.out.flags & safety_flags::kRateLimited) flags |= status_flags::kRateLimited;
  if (f.lost_joints != 0) flags |= status_flags::kEstimateLost;
  if (clock_reset_in_period_) flags |= status_flags::kClockReset;
  if (overrun_in_period_) flags |= status_flags::kOverrun;
  if (oscillation_.tripped()) flags |= status_flags::kOscillation;
  if (passivity_in_period_) flags |= status_flags::kPassivityActive;
  if (machine_.fault() == FaultReason::kSlaveSession ||
      machine_.fault() == FaultReason::kMasterSession)
    flags |= status_flags::kOtherSession;
  return flags;
}

void HapticLoop::publish_status(const TickFacts& f) noexcept {
  const std::int64_t now_ns = f.now_ns;
  const auto lat = window_lateness_.summary();
  const auto cmp = window_compute_.summary();
  // Percentiles in HAPTIC_STATUS cover the last second, not the whole run.
  if ((status_seq_ + 1) % 100 == 0) {
    window_lateness_.reset();
    window_compute_.reset();
  }
  const auto link = link_.stats();
  status_.utime = now_ns / 1000;
  status_.seq = status_seq_++;
  status_.num_joints = config_.joints;
  status_.state = static_cast<std::int32_t>(f.state);
  status_.feedback_source = static_cast<std::int32_t>(config_.source);
  // Over the last status period, as documented: a stall shows here at once
  // instead of being averaged away over the whole run.
  status_.rate_hz = status_ns_ > 0 && now_ns > status_ns_
                        ? static_cast<double>(counters_.ticks - status_ticks_) /
                              (static_cast<double>(now_ns - status_ns_) * 1e-9)
                        : measured_rate_hz();
  status_ticks_ = counters_.ticks;
  status_ns_ = now_ns;
  status_.lateness_p50_us = lat.p50_us;
  status_.lateness_p99_us = lat.p99_us;
  status_.lateness_max_us = lat.max_us;
  status_.compute_p99_us = cmp.p99_us;
  status_.overruns = static_cast<std::int64_t>(counters_.overruns);
  status_.slave_age_ms = have_state_ ? f.slave_age_s * 1e3 : -1.0;
  status_.slave_rejected = link.rejected;
  status_.slave_seq_gaps = link.seq_gaps;
  status_.slave_latency_p99_us = link.latency_p99_us;
  status_.flags = status_flags_of(f) | calibration_status(status_);
  // The period's events are reported once.
  clock_reset_in_period_ = false;
  overrun_in_period_ = false;
  passivity_in_period_ = false;
  status_.oscillation_trips = static_cast<std::int64_t>(oscillation_.trips());
  for (std::size_t j = 0; j < static_cast<std::size_t>(config_.joints); ++j) {
    status_.tau_in[j] = estimates_[j].tau_in;
    status_.tau_out_est[j] = estimates_[j].tau_out_est;
    status_.friction_est[j] = estimates_[j].friction;
    status_.torque_cmd[j] = f.out.torque[j];
    status_.master_q[j] = reading_.q[j];
    status_.passivity_energy[j] = passivity_[j].observed_energy();
    status_.passivity_dissipated[j] = passivity_[j].dissipated();
    status_.oscillation_rms[j] = oscillation_.band_rms(static_cast<int>(j));
  }
  link_.publish_status(status_);
  // The same figures for the server's live status line (main thread).
  events_.ticks.store(counters_.ticks, std::memory_order_relaxed);
  events_.rate_hz.store(status_.rate_hz, std::memory_order_relaxed);
  events_.lateness_p99_us.store(lat.p99_us, std::memory_order_relaxed);
  events_.lateness_max_us.store(lat.max_us, std::memory_order_relaxed);
  events_.slave_age_ms.store(status_.slave_age_ms, std::memory_order_relaxed);
  for (std::size_t j = 0; j < static_cast<std::size_t>(config_.joints); ++j)
    events_.torque_nm[j].store(f.out.torque[j], std::memory_order_relaxed);
}

void HapticLoop::shutdown() noexcept {
  if (shut_down_) return;
  device_torque_.fill(0.0);
  device_.write_torque(device_torque_);
  device_.set_enabled(false);
  device_enabled_ = false;
  // Strictly after the last tick's command: a receiver drops a message whose
  // seq advances while its utime does not (time_backwards), and this one --
  // the slave told to hold -- must never be dropped.
  command_.utime = last_ns_ / 1000 + 1;
  command_.seq = command_seq_++;
  command_.num_joints = config_.joints;
  command_.enable = false;
  command_.clutch = false;
  link_.publish_command(command_);
  shut_down_ = true;
}

}  // namespace tsmh::haptics
