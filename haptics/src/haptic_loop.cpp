#include "haptics/haptic_loop.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace tsmh::haptics {

std::string_view to_string(FeedbackSource s) noexcept {
  switch (s) {
    case FeedbackSource::kEstimated:
      return "estimated";
    case FeedbackSource::kNaive:
      return "naive";
    case FeedbackSource::kNone:
      return "none";
  }
  return "?";
}

HapticLoop::HapticLoop(const LoopConfig& config, master_devices::Device& device, SlaveLink& link,
                       std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> estimators,
                       TraceSink* trace)
    : config_(config),
      device_(device),
      link_(link),
      estimators_(std::move(estimators)),
      trace_(trace),
      safety_(config.joints, config.limits, config.timing),
      oscillation_(config.joints, config.oscillation, config.rate_hz) {
  if (static_cast<int>(estimators_.size()) != config_.joints)
    throw std::invalid_argument("haptic loop: one estimator per joint is needed");
  for (const auto& e : estimators_)
    if (!e) throw std::invalid_argument("haptic loop: missing estimator");
  if (!(config_.rate_hz >= 1.0 && config_.rate_hz <= 4000.0))
    throw std::invalid_argument("rate_hz: must be within 1..4000");
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

void HapticLoop::tick(std::int64_t now_ns, std::int64_t lateness_ns) noexcept {
  if (shut_down_) return;
  const double nominal_dt = 1.0 / config_.rate_hz;
  const double dt =
      counters_.ticks == 0 ? nominal_dt : static_cast<double>(now_ns - last_ns_) * 1e-9;
  if (counters_.ticks == 0) first_ns_ = now_ns;
  last_ns_ = now_ns;
  ++counters_.ticks;
  lateness_.record(lateness_ns);
  window_lateness_.record(lateness_ns);
  if (lateness_ns > events_.worst_lateness_ns.load(std::memory_order_relaxed))
    events_.worst_lateness_ns.store(lateness_ns, std::memory_order_relaxed);
  const auto n = static_cast<std::size_t>(config_.joints);

  // 1. The master.
  reading_ = device_.read(now_ns);

  // 2. The newest slave state; the estimator runs once per new sample, on the
  //    slave's own clock (utime), so its differentiator sees true intervals.
  const std::uint64_t version = link_.latest_state(state_);
  if (version != 0 && version != state_version_) {
    state_version_ = version;
    ++counters_.slave_samples;
    events_.slave_samples.store(counters_.slave_samples, std::memory_order_relaxed);
    estimate();
  }
  const double age_s = have_state_ ? static_cast<double>(now_ns - state_.receive_ns) * 1e-9
                                   : std::numeric_limits<double>::infinity();

  // Loss of the estimate (issue 15): the last valid estimate is held and
  // faded exactly like a stale slave (the fade counts from the loss), and the
  // loop faults if it lasts estimate_fault_s. The flag goes out in
  // HAPTIC_STATUS and the server logs it from its main thread.
  std::uint32_t lost = 0;
  if (have_state_ && config_.source != FeedbackSource::kNone)
    for (std::size_t j = 0; j < n; ++j)
      if (!estimates_[j].valid) lost |= 1U << j;
  if (lost != 0) {
    if (estimate_lost_since_ns_ < 0) estimate_lost_since_ns_ = now_ns;
    ++counters_.estimate_lost_ticks;
  } else {
    estimate_lost_since_ns_ = -1;
  }
  const double lost_s =
      lost != 0 ? static_cast<double>(now_ns - estimate_lost_since_ns_) * 1e-9 : 0.0;
  events_.estimate_lost_joints.store(lost, std::memory_order_relaxed);

  // 3. Feedback request per joint (NaN passes through: the safety filter zeroes it).
  JointArray request{};
  for (std::size_t j = 0; j < n; ++j)
    request[j] = config_.force[j](slave_torque(j));

  // 4. State machine. A late master reading zeroes torque this tick (below)
  // without latching a fault unless it persists.
  const bool device_fresh = reading_.status == master_devices::DeviceStatus::kOk;
  const bool device_late =
      reading_.status == master_devices::DeviceStatus::kDisconnected && reading_.stale;
  if (device_late) {
    if (device_stale_since_ns_ < 0) device_stale_since_ns_ = now_ns;
    ++counters_.device_stale_ticks;
  } else {
    device_stale_since_ns_ = -1;
  }
  const bool device_ok =
      device_fresh || (device_late && static_cast<double>(now_ns - device_stale_since_ns_) * 1e-9 <
                                          config_.device_stale_fault_s);
  const LoopState before = machine_.state();
  const LoopState now_state =
      machine_.update({.dead_man = reading_.buttons.dead_man,
                       .e_stop = reading_.buttons.e_stop,
                       .device_ok = device_ok,
                       .slave_lost = !(age_s <= config_.slave_timeout_s) &&
                                     counters_.ticks * nominal_dt > config_.slave_timeout_s,
                       .estimate_lost = lost_s > config_.estimate_fault_s});
  if (now_state == LoopState::kFault && before != LoopState::kFault) {
    ++counters_.faults;
    events_.faults.store(counters_.faults, std::memory_order_relaxed);
  }
  events_.state.store(static_cast<std::int32_t>(now_state), std::memory_order_relaxed);
  events_.fault.store(static_cast<std::int32_t>(machine_.fault()), std::memory_order_relaxed);
  const bool enabled = now_state == LoopState::kEnabled;
  if (enabled && before != LoopState::kEnabled) {
    // Start from where the slave is, so enabling never makes it jump.
    for (std::size_t j = 0; j < n; ++j) {
      const double slave_at = std::isfinite(state_.x_out[j]) && have_state_
                                  ? state_.x_out[j]
                                  : position_[j].reference();
      position_[j].align(reading_.q[j], slave_at);
    }
  }
  if (enabled != device_enabled_) {
    device_.set_enabled(enabled);
    device_enabled_ = enabled;
  }

  // 5. Oscillation fade and passivity control, safety, then the device.
  shape_request(request, dt, enabled && device_fresh);
  const SafetyOutput& out =
      safety_.apply(request, dt, std::max(age_s, lost_s), enabled && device_fresh);
  observe_rendered(out);
  if (out.flags & safety_flags::kNonFinite) ++counters_.nonfinite_requests;
  if (out.flags & safety_flags::kSaturated) ++counters_.saturated_ticks;
  if (out.flags & safety_flags::kRateLimited) ++counters_.rate_limited_ticks;
  if (out.flags & safety_flags::kStaleFade) ++counters_.stale_ticks;
  for (std::size_t j = 0; j < master_devices::kMaxDof; ++j)
    device_torque_[j] = j < n ? out.torque[j] : 0.0;
  device_.write_torque(device_torque_);

  // 6. Position command to the slave.
  command_.utime = now_ns / 1000;
  command_.seq = command_seq_++;
  command_.num_joints = config_.joints;
  command_.enable = enabled;
  command_.clutch = reading_.buttons.clutch;
  for (std::size_t j = 0; j < n; ++j)
    command_.position_ref[j] = enabled ? position_[j].update(reading_.q[j], reading_.buttons.clutch)
                                       : position_[j].reference();
  link_.publish_command(command_);

  // 7. Status at 100 Hz.
  if (counters_.ticks % static_cast<std::uint64_t>(config_.status_every) == 0)
    publish_status(now_ns);

  // 8. Trace (evaluation, plots).
  if (trace_) {
    const std::uint64_t tv = link_.latest_truth(truth_);
    const bool truth_matches = tv != 0 && have_state_ && truth_.seq == state_.seq;
    TraceRow row;
    row.t = static_cast<double>(now_ns - first_ns_) * 1e-9;
    row.state_seq = have_state_ ? state_.seq : -1;
    row.state = static_cast<std::int32_t>(now_state);
    row.flags = static_cast<std::int32_t>(out.flags);
    row.lateness_us = static_cast<double>(lateness_ns) * 1e-3;
    constexpr double nan = std::numeric_limits<double>::quiet_NaN();
    for (std::size_t j = 0; j < n; ++j) {
      auto& r = row.joints[j];
      r.master_q = reading_.q[j];
      r.slave_ref = command_.position_ref[j];
      r.tau_in = estimates_[j].tau_in;
      r.tau_out_est = estimates_[j].tau_out_est;
      r.torque_cmd = out.torque[j];
      r.x_in = have_state_ ? state_.x_in[j] : nan;
      r.x_out = have_state_ ? state_.x_out[j] : nan;
      r.true_tau_out = truth_matches ? truth_.tau_out[j] : nan;
      r.true_x_out = truth_matches ? truth_.x_out[j] : nan;
      r.indentation = truth_matches ? truth_.indentation[j] : nan;
      r.contact_force = truth_matches ? truth_.contact_force[j] : nan;
    }
    trace_->append(row);
  }
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
    e = joints_ok ? estimators_[j]->update_tensions(static_cast<double>(state_.utime) * 1e-6,
                                                    state_.x_in[j], state_.T1[j], state_.T3[j])
                  : estimator::Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
    if (e.valid) {
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

void HapticLoop::publish_status(std::int64_t now_ns) noexcept {
  const auto lat = window_lateness_.summary();
  const auto cmp = window_compute_.summary();
  // Percentiles in HAPTIC_STATUS cover the last second, not the whole run.
  if ((status_seq_ + 1) % 100 == 0) {
    window_lateness_.reset();
    window_compute_.reset();
  }
  const auto link = link_.stats();
  const auto& out = safety_.last();
  status_.utime = now_ns / 1000;
  status_.seq = status_seq_++;
  status_.num_joints = config_.joints;
  status_.state = static_cast<std::int32_t>(machine_.state());
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
  status_.slave_age_ms =
      have_state_ ? static_cast<double>(now_ns - state_.receive_ns) * 1e-6 : -1.0;
  status_.slave_rejected = link.rejected;
  status_.slave_seq_gaps = link.seq_gaps;
  status_.slave_latency_p99_us = link.latency_p99_us;
  std::int32_t flags = 0;
  if (out.flags & safety_flags::kStaleFade) flags |= status_flags::kStaleFade;
  if (reading_.buttons.e_stop) flags |= status_flags::kEStop;
  if (!reading_.buttons.dead_man) flags |= status_flags::kDeadManReleased;
  if (out.flags & safety_flags::kSaturated) flags |= status_flags::kSaturated;
  if (out.flags & safety_flags::kRateLimited) flags |= status_flags::kRateLimited;
  if (estimate_lost_since_ns_ >= 0) flags |= status_flags::kEstimateLost;
  if (clock_reset_in_period_) flags |= status_flags::kClockReset;
  if (overrun_in_period_) flags |= status_flags::kOverrun;
  if (oscillation_.tripped()) flags |= status_flags::kOscillation;
  if (passivity_in_period_) flags |= status_flags::kPassivityActive;
  clock_reset_in_period_ = false;
  overrun_in_period_ = false;
  passivity_in_period_ = false;
  status_.oscillation_trips = static_cast<std::int64_t>(oscillation_.trips());
  status_.flags = flags;
  for (std::size_t j = 0; j < static_cast<std::size_t>(config_.joints); ++j) {
    status_.tau_in[j] = estimates_[j].tau_in;
    status_.tau_out_est[j] = estimates_[j].tau_out_est;
    status_.friction_est[j] = estimates_[j].friction;
    status_.torque_cmd[j] = out.torque[j];
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
    events_.torque_nm[j].store(out.torque[j], std::memory_order_relaxed);
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
