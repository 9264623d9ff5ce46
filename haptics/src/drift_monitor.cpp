#include "haptics/drift_monitor.hpp"

#include <cmath>

namespace tsmh::haptics {

void DriftMonitor::reset() noexcept {
  *this = DriftMonitor(config_);
}

void DriftMonitor::update(double t, const estimator::Estimate& e, double radius_m) noexcept {
  if (!config_.enabled || !e.valid || !std::isfinite(t)) return;
  const double dt = started_ ? t - t_last_ : 0.0;
  if (started_ && !(dt > 0.0)) return;
  started_ = true;
  t_last_ = t;
  // Forget in time, whether or not this sample counts: old data fades while
  // the joint rests or presses.
  const double keep = std::exp(-dt / config_.time_constant_s);
  s0_ *= keep, sf_ *= keep, sff_ *= keep, sr_ *= keep, srf_ *= keep;
  w_pos_ *= keep, w_neg_ *= keep;

  const double f = radius_m * e.friction;  // the model's friction torque, N m
  const double r = e.tau_in - f;           // = the estimated distal torque
  const bool sliding = std::fabs(e.xd) > config_.min_speed_rad_s;
  // NaN level (a model without one) compares false: no saturation gate.
  const bool in_transition =
      std::fabs(e.friction) < config_.min_saturation * std::fabs(e.friction_level);
  if (sliding && !in_transition && std::fabs(r) <= config_.contact_gate_ratio * std::fabs(f) &&
      std::isfinite(f) && std::isfinite(r)) {
    s0_ += 1.0, sf_ += f, sff_ += f * f, sr_ += r, srf_ += r * f;
    (e.xd > 0.0 ? w_pos_ : w_neg_) += 1.0;
  }
  const double det = s0_ * sff_ - sf_ * sf_;
  judged_ = w_pos_ >= config_.min_weight_per_direction &&
            w_neg_ >= config_.min_weight_per_direction && det > 0.0;
  if (!judged_) return;  // keep the alarm as it is until the data can tell
  c_ = (s0_ * srf_ - sf_ * sr_) / det;

  const double off = std::fabs(c_);
  if (off > config_.threshold) {
    within_since_ = -1.0;
    if (beyond_since_ < 0.0) beyond_since_ = t;
    if (t - beyond_since_ >= config_.hold_s) alarm_ = true;
  } else {
    beyond_since_ = -1.0;
    if (off < 0.5 * config_.threshold) {
      if (within_since_ < 0.0) within_since_ = t;
      if (t - within_since_ >= config_.hold_s) alarm_ = false;
    } else {
      within_since_ = -1.0;
    }
  }
}

}  // namespace tsmh::haptics
