#pragma once
// Integration of the internal state of eq. (4) over one sample interval.
//
//   dz/dt = theta g (1 - |w|^n + sigma |w|^(n-1) (sgn(w) - sgn(g)) w),  w = z / Ff
//
// With g and Ff held over the interval, substitute u = sgn(g) w and
// a = theta |g| t / Ff: the state obeys the autonomous 1-D ODE
//   du/da = h(u),  h(u) = 1 - u^n          for u >= 0
//                  h(u) = 1 + (2 sigma - 1) |u|^n for u < 0,
// whose solution moves monotonically towards the fixed point u = 1 when
// sigma >= 1/2. We integrate it with RK4 in a (a few sub-steps only when the
// travel a is large: dropped samples, high speed) and clamp to the interval
// between the start value and the fixed point, so the state is bounded for
// any dt and any input. sigma < 1/2 makes the state unbounded; parameter
// validation refuses it.

#include <algorithm>
#include <cmath>

namespace tsmh::estimator {

struct BoucWenShape {
  double theta = 1.0;  ///< rate (1/rad)
  double n = 2.0;      ///< sharpness exponent, >= 1
  double sigma = 1.0;  ///< loading/unloading shape, >= 0.5
};

/// Largest RK4 step in normalised travel a (error about 1e-7 per step).
inline constexpr double kMaxRk4Travel = 0.1;

/// z after `dt` seconds with drive g (rad/s) and sliding level ff (> 0)
/// held, for any shape and any interval: RK4 sub-steps or the closed form.
double advance_bouc_wen_state_general(double z, double ff, double g, double dt,
                                      const BoucWenShape& shape) noexcept;

/// z after `dt` seconds with drive g (rad/s) and sliding level ff (> 0) held.
/// The same result as advance_bouc_wen_state_general(), bit for bit.
inline double advance_bouc_wen_state(double z, double ff, double g, double dt,
                                     const BoucWenShape& shape) noexcept {
  // Fast path, inline and straight-line because the haptic loop takes it on
  // nearly every tick: the paper's shape (n = 2, sigma = 1, where
  // h(u) = 1 - u |u|), |u0| <= 2 (the general loop's step limit is
  // kMaxRk4Travel up to 2.5) and a travel of at most one RK4 step. It
  // performs exactly the operations the general loop performs in that case,
  // in the same order, without its branches on the shape and the sub-steps
  // (test_model_fast_path.cpp pins the equality).
  if (shape.n == 2.0 && shape.sigma == 1.0 && g != 0.0 && dt > 0.0 && ff > 0.0) {
    const double dir = g > 0.0 ? 1.0 : -1.0;
    const double u0 = dir * z / ff;
    const double da = shape.theta * std::fabs(g) * dt / ff;
    if (std::fabs(u0) <= 2.0 && da > 0.0 && da <= kMaxRk4Travel) {
      const auto h = [](double u) { return 1.0 - u * std::fabs(u); };
      const double k1 = h(u0);
      const double k2 = h(u0 + 0.5 * da * k1);
      const double k3 = h(u0 + 0.5 * da * k2);
      const double k4 = h(u0 + da * k3);
      const double u = u0 + da / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      // Between the start and the fixed point 1, as the general path's
      // std::clamp (min(max(u, lo), hi)), on values and without a branch:
      // u0 falls on either side of 1 at random from tick to tick in
      // sliding, and std::clamp's reference result stays in memory.
      const double lo = std::min(u0, 1.0), hi = std::max(u0, 1.0);
      return dir * std::min(std::max(u, lo), hi) * ff;
    }
  }
  return advance_bouc_wen_state_general(z, ff, g, dt, shape);
}

/// Right-hand side dz/dt of eq. (4), literally as printed (for references and tests).
double bouc_wen_rate(double z, double ff, double g, const BoucWenShape& shape) noexcept;

}  // namespace tsmh::estimator
