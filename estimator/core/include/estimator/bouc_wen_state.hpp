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

namespace tsmh::estimator {

struct BoucWenShape {
  double theta = 1.0;  ///< rate (1/rad)
  double n = 2.0;      ///< sharpness exponent, >= 1
  double sigma = 1.0;  ///< loading/unloading shape, >= 0.5
};

/// z after `dt` seconds with drive g (rad/s) and sliding level ff (> 0) held.
double advance_bouc_wen_state(double z, double ff, double g, double dt,
                              const BoucWenShape& shape) noexcept;

/// Right-hand side dz/dt of eq. (4), literally as printed (for references and tests).
double bouc_wen_rate(double z, double ff, double g, const BoucWenShape& shape) noexcept;

}  // namespace tsmh::estimator
