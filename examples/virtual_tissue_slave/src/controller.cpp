#include "virtual_tissue_slave/controller.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "field_checks.hpp"

namespace tsmh::virtual_tissue_slave {

void validate(const ControllerParams& p) {
  const FieldChecks check("controller");
  check.non_negative(p.kp, "kp");
  check.non_negative(p.kd, "kd");
  check.positive(p.velocity_filter_hz, "velocity_filter_hz");
  check.non_negative(p.backlash_initial_rad, "backlash_initial_rad");
  check.non_negative(p.backlash_max_rad, "backlash_max_rad");
  check.require(p.backlash_initial_rad <= p.backlash_max_rad, "backlash_initial_rad",
                "must be <= backlash_max_rad");
  check.non_negative(p.adapt_gain, "adapt_gain");
  check.positive(p.switch_width_rad, "switch_width_rad");
  check.positive(p.adapt_velocity, "adapt_velocity");
  check.non_negative(p.output_kp, "output_kp");
  check.non_negative(p.output_ki, "output_ki");
  check.non_negative(p.integral_limit_rad, "integral_limit_rad");
}

JointController::JointController(const ControllerParams& params) : params_(params) {
  validate(params);
}

void JointController::reset(const Measurement& m, double reference) {
  started_ = true;
  last_ref_ = reference;
  side_ = 0.0;
  last_x_in_ = m.x_in;
  velocity_ = 0.0;
  c_hat_ = params_.backlash_initial_rad;
  integral_ = 0.0;
  motor_ref_ = reference;
}

namespace {
// First-order low-pass gain for one step of dt at cut-off fc.
double lowpass_gain(double fc_hz, double dt) {
  return 1.0 - std::exp(-2.0 * std::numbers::pi * fc_hz * dt);
}
}  // namespace

double JointController::update(double reference, const Measurement& m, double radius_m, double dt) {
  if (!started_) reset(m, reference);
  const double step = reference - last_ref_;
  last_ref_ = reference;
  if (step != 0.0) {
    const double target = step > 0 ? 1.0 : -1.0;
    side_ += std::min(1.0, std::abs(step) / params_.switch_width_rad) * (target - side_);
  }
  const double raw_velocity = (m.x_in - last_x_in_) / dt;
  last_x_in_ = m.x_in;
  velocity_ += lowpass_gain(params_.velocity_filter_hz, dt) * (raw_velocity - velocity_);

  motor_ref_ = reference;
  if (params_.compensation) {
    const double direction = side_;
    if (std::isfinite(m.x_out)) {
      const double e = reference - m.x_out;
      const double moving = std::min(1.0, std::abs(step) / dt / params_.adapt_velocity);
      c_hat_ = std::clamp(c_hat_ + dt * params_.adapt_gain * moving * e * direction, 0.0,
                          params_.backlash_max_rad);
      integral_ = std::clamp(integral_ + dt * params_.output_ki * e, -params_.integral_limit_rad,
                             params_.integral_limit_rad);
      motor_ref_ += params_.output_kp * e + integral_;
    }
    motor_ref_ += c_hat_ * direction;
  }
  double torque = params_.kp * (motor_ref_ - m.x_in) - params_.kd * velocity_;
  if (params_.tension_feedforward) torque += radius_m * (m.T1 - m.T3);
  return torque;
}

}  // namespace tsmh::virtual_tissue_slave
