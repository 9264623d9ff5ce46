#pragma once
// What a friction model sees at one sample: the input pulley's motion (from
// the differentiator, or exact), the transmitted load, the distal angle where
// it is measured, and the time.

#include <limits>

namespace tsmh::estimator {

struct Motion {
  double t = 0.0;    ///< s, for time-varying terms
  double x = 0.0;    ///< rad, input pulley angle
  double xd = 0.0;   ///< rad/s
  double xdd = 0.0;  ///< rad/s^2 (magnitude used by the acceleration terms)
  /// sgn(xdd) as the model switches on it: -1, 0 or +1 (exact derivatives,
  /// the paper's model). The differentiator's smoothed variant passes the
  /// expected sign in [-1, 1] when the estimate cannot tell (near a zero
  /// crossing); eqs. (4)-(10) are linear in sgn(xdd), so the model takes
  /// either (docs/friction-model.md).
  double acc_sign = 0.0;
  double load = 0.0;  ///< N, transmitted load |tau_in| / R, for load-dependent terms
  /// N, the signed proximal drive tau_in / R, from which the distributed-slip
  /// terms solve the distal load (distributed_slip.hpp); NaN: unknown.
  double drive = std::numeric_limits<double>::quiet_NaN();
  /// N, the mean of the two proximal tensions (T1 + T3) / 2, which the
  /// distributed-slip tension copies scale with; NaN: not measured.
  double tension = std::numeric_limits<double>::quiet_NaN();
  /// N, the measured distal load tau_out / R, where a fit has it (a
  /// calibration recording with a tip sensor); NaN online, where a model
  /// that reads the distal load takes it as drive less its own friction. In a
  /// fit the measured one keeps the model from reading its own error through
  /// drive - F.
  double distal = std::numeric_limits<double>::quiet_NaN();
  /// rad, the distal joint angle where a joint encoder measures it; NaN:
  /// not measured. A model that drives part of the sheath from the tip reads
  /// it (slip that the tip load drives while the input pulley stands still);
  /// NaN reads as a rigid tendon, x_out = x.
  double x_out = std::numeric_limits<double>::quiet_NaN();
};

/// sgn with sgn(0) = 0, as in the paper.
constexpr double sign_of(double v) {
  return (v > 0.0) - (v < 0.0);
}

}  // namespace tsmh::estimator
