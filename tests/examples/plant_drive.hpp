#pragma once
// Test helper: drives a JointPlant's input pulley along a prescribed angle
// with a stiff motor servo, so physics tests can impose the input motion.

#include <functional>

#include "virtual_tissue_slave/joint_plant.hpp"

namespace tsmh::virtual_tissue_slave::testing {

inline constexpr double kPhysicsDt = 1e-4;

/// One physics step towards input angle `x_ref` (rad).
inline void drive_step(JointPlant& plant, double x_ref) {
  const JointTruth& t = plant.truth();
  const double torque = 200.0 * (x_ref - t.x_in) - 2.0 * t.xd_in + t.tau_in;
  plant.step(torque, kPhysicsDt);
}

/// Drives the input along `x_of_t` for `seconds`, calling `each(t)` after every step.
inline void drive(JointPlant& plant, const std::function<double(double)>& x_of_t, double seconds,
                  const std::function<void(double)>& each = {}) {
  const long n = static_cast<long>(seconds / kPhysicsDt + 0.5);
  for (long k = 1; k <= n; ++k) {
    const double t = static_cast<double>(k) * kPhysicsDt;
    drive_step(plant, x_of_t(t));
    if (each) each(t);
  }
}

}  // namespace tsmh::virtual_tissue_slave::testing
