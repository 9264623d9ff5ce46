#pragma once
// Distal torque estimated at the slave -> torque rendered on the master joint.

#include <cmath>

namespace tsmh::haptics {

struct ForceMapping {
  double scale = 1.0;     ///< master N m per slave N m (force scaling)
  double sign = 1.0;      ///< +1 or -1: master and slave joint conventions
  double deadband = 0.0;  ///< slave N m below which nothing is rendered (estimation noise)

  /// Continuous deadband (no step at its edge): |tau| - deadband, keeping the sign.
  double operator()(double slave_torque) const noexcept {
    const double mag = std::fabs(slave_torque) - deadband;
    if (!(mag > 0.0)) return std::isnan(slave_torque) ? slave_torque : 0.0;
    return sign * scale * std::copysign(mag, slave_torque);
  }
};

}  // namespace tsmh::haptics
