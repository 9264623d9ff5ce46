#pragma once
// Distal torque estimated at the slave -> torque rendered on the master joint.
//
// The master renders the tissue's reaction, not the slave's action: a distal
// torque with which the tool presses into tissue in its + direction pushes
// the surgeon's hand back, in the master's - direction when the two joints
// turn the same way (sign +1, as position_sign +1). Rendering the action
// instead would pull the hand into the tissue (positive feedback).

#include <cmath>

namespace tsmh::haptics {

struct ForceMapping {
  double scale = 1.0;     ///< master N m per slave N m (force scaling)
  double sign = 1.0;      ///< +1: master and slave joints turn the same way, -1: opposite
  double deadband = 0.0;  ///< slave N m below which nothing is rendered (estimation noise)

  /// Continuous deadband (no step at its edge): |tau| - deadband, keeping the sign.
  double operator()(double slave_torque) const noexcept {
    const double mag = std::fabs(slave_torque) - deadband;
    if (!(mag > 0.0)) return std::isnan(slave_torque) ? slave_torque : 0.0;
    return -sign * scale * std::copysign(mag, slave_torque);
  }
};

}  // namespace tsmh::haptics
