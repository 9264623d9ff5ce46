// The loop's issue-21 stages, kept apart from haptic_loop.cpp so that other
// loop changes merge without touching them: the oscillation fade and the
// time-domain passivity controller (before safety), and the two-port
// observer's bookkeeping (slave port per new SLAVE_STATE, master port per
// rendered tick). Nothing here allocates, locks or prints.

#include <cmath>

#include "haptics/haptic_loop.hpp"

namespace tsmh::haptics {

void HapticLoop::observe_slave_ports() noexcept {
  for (std::size_t j = 0; j < static_cast<std::size_t>(config_.joints); ++j) {
    // The slave port in master units: the torque as the master renders it,
    // the slave angle in master radians. The joint encoder when the slave
    // has one, else the motor angle (it includes the backlash).
    const double x = std::isfinite(state_.x_out[j]) ? state_.x_out[j] : state_.x_in[j];
    const auto& pm = config_.position[j];
    const double gain = pm.sign * pm.scale;
    passivity_[j].slave_sample(config_.force[j](slave_torque(j)), x / gain);
  }
}

void HapticLoop::shape_request(JointArray& request, double dt, bool enabled) noexcept {
  const auto n = static_cast<std::size_t>(config_.joints);
  // Oscillation: judged on what was rendered up to the previous tick. While
  // torque is disabled its filters rest, so the step to zero at a release or
  // a fault never reads as an oscillation.
  if (!enabled) oscillation_.reset_signal();
  const double gain = oscillation_.update(safety_.last().torque, dt);
  if (gain < 1.0) ++counters_.oscillation_ticks;
  if (oscillation_.trips() > counters_.oscillation_trips)
    counters_.oscillation_trips = oscillation_.trips();
  // Passivity: a fresh energy account from each enabling, so energy stored
  // in an earlier session is no licence to be active now.
  if (enabled && !passivity_enabled_)
    for (std::size_t j = 0; j < n; ++j)
      passivity_[j].reset();
  passivity_enabled_ = enabled;
  bool active = false;
  for (std::size_t j = 0; j < n; ++j) {
    request[j] = passivity_[j].control(reading_.q[j], request[j] * gain, dt);
    active = active || passivity_[j].active();
  }
  if (active) {
    ++counters_.passivity_ticks;
    passivity_in_period_ = true;
  }
}

void HapticLoop::observe_rendered(const SafetyOutput& out) noexcept {
  for (std::size_t j = 0; j < static_cast<std::size_t>(config_.joints); ++j)
    passivity_[j].commit(out.torque[j]);
}

}  // namespace tsmh::haptics
