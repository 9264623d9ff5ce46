#pragma once
// Pure conversions between the device's units (encoder counts, motor
// milliamps) and the joint's (rad, N m), and the two stateful filters a
// console driver needs per joint. No allocation; safe on any thread.

#include <cstdint>

#include "master_devices/profile.hpp"

namespace tsmh::master_devices {

/// Joint angle, rad, from a raw encoder count.
double counts_to_rad(const JointProfile& j, std::int32_t counts);
/// Raw encoder count at a joint angle (the inverse, rounded).
std::int32_t rad_to_counts(const JointProfile& j, double q_rad);
/// Motor current, A, that produces joint torque tau (no limits applied).
double torque_to_current_a(const JointProfile& j, double tau_nm);
/// Joint torque, N m, from motor current.
double current_to_torque_nm(const JointProfile& j, double current_a);
/// Amperes to the protocol's signed milliamps, rounded and clamped to its range.
std::int16_t to_milliamps(double current_a);

/// Peak clamp always, plus an I^2 t limit: when the low-pass filtered I^2
/// (time constant `tau_s`) exceeds the continuous limit squared, currents
/// fold back to the continuous limit until it has cooled to 90 % of it.
/// This is what lets a console give short peaks without cooking its motors.
class CurrentLimiter {
 public:
  CurrentLimiter() = default;
  CurrentLimiter(double continuous_a, double peak_a, double tau_s);
  /// The current allowed for a request of `current_a` held for `dt_s`.
  double limit(double current_a, double dt_s) noexcept;
  void reset() {
    i2_ = 0.0;
    folded_back_ = false;
  }

 private:
  double continuous_a_ = 0.0;
  double peak_a_ = 0.0;
  double tau_s_ = 1.0;
  double i2_ = 0.0;
  bool folded_back_ = false;
};

/// Velocity from successive angle samples on the device's own clock (USB
/// delivery jitter must not show up as velocity), low-pass filtered because
/// one encoder count per millisecond is already a visible velocity step.
class VelocityEstimator {
 public:
  VelocityEstimator() = default;
  explicit VelocityEstimator(double cutoff_hz) : cutoff_hz_(cutoff_hz) {}
  /// Feeds a sample; dt_s is the device time since the previous one (<= 0: ignored).
  double update(double q_rad, double dt_s) noexcept;
  double value() const { return qd_; }
  void reset() {
    primed_ = false;
    qd_ = 0.0;
  }

 private:
  double cutoff_hz_ = 150.0;
  double q_prev_ = 0.0;
  double qd_ = 0.0;
  bool primed_ = false;
};

}  // namespace tsmh::master_devices
