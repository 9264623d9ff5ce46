#include "master_devices/joint_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "master_devices/protocol.hpp"

namespace tsmh::master_devices {

double counts_to_rad(const JointProfile& j, std::int32_t counts) {
  return j.direction * (static_cast<double>(counts) - j.zero_offset_counts) / j.counts_per_rad;
}

std::int32_t rad_to_counts(const JointProfile& j, double q_rad) {
  return static_cast<std::int32_t>(
      std::lround(j.zero_offset_counts + j.direction * q_rad * j.counts_per_rad));
}

double torque_to_current_a(const JointProfile& j, double tau_nm) {
  return j.direction * tau_nm / j.torque_constant_nm_per_a;
}

double current_to_torque_nm(const JointProfile& j, double current_a) {
  return j.direction * current_a * j.torque_constant_nm_per_a;
}

std::int16_t to_milliamps(double current_a) {
  if (!std::isfinite(current_a)) return 0;
  const double ma = std::clamp(current_a * 1000.0, double{-protocol::kMaxCurrentMa},
                               double{protocol::kMaxCurrentMa});
  return static_cast<std::int16_t>(std::lround(ma));
}

CurrentLimiter::CurrentLimiter(double continuous_a, double peak_a, double tau_s)
    : continuous_a_(continuous_a), peak_a_(peak_a), tau_s_(tau_s) {}

double CurrentLimiter::limit(double current_a, double dt_s) noexcept {
  if (!std::isfinite(current_a)) current_a = 0.0;
  const double cont2 = continuous_a_ * continuous_a_;
  if (folded_back_ && i2_ < 0.9 * cont2) folded_back_ = false;
  if (!folded_back_ && i2_ > cont2) folded_back_ = true;
  const double cap = folded_back_ ? continuous_a_ : peak_a_;
  const double out = std::clamp(current_a, -cap, cap);
  const double alpha = std::clamp(dt_s / tau_s_, 0.0, 1.0);
  i2_ += alpha * (out * out - i2_);
  return out;
}

double VelocityEstimator::update(double q_rad, double dt_s) noexcept {
  if (!primed_) {
    q_prev_ = q_rad;
    qd_ = 0.0;
    primed_ = true;
    return qd_;
  }
  if (dt_s <= 0.0) return qd_;
  const double raw = (q_rad - q_prev_) / dt_s;
  q_prev_ = q_rad;
  const double rc = 1.0 / (2.0 * std::numbers::pi * cutoff_hz_);
  qd_ += (dt_s / (dt_s + rc)) * (raw - qd_);
  return qd_;
}

}  // namespace tsmh::master_devices
