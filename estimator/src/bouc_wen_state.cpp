#include "estimator/bouc_wen_state.hpp"

#include <algorithm>
#include <cmath>

namespace tsmh::estimator {
namespace {

double abs_pow(double a, double n) noexcept {
  // n = 1 and n = 2 are the cases in use (Dahl, the paper); avoid pow() there.
  if (n == 2.0) return a * a;
  if (n == 1.0) return a;
  return std::pow(a, n);
}

// du/da in the normalised coordinates (see header).
double h(double u, const BoucWenShape& s) noexcept {
  const double p = abs_pow(std::fabs(u), s.n);
  return u >= 0.0 ? 1.0 - p : 1.0 + (2.0 * s.sigma - 1.0) * p;
}

// Largest RK4 step: 0.1 in normalised travel (error about 1e-7 per step), and
// less where the state is far beyond Ff so that the local stiffness
// |dh/du| * step stays <= 0.5, far inside RK4's stability region.
double max_step(double u, const BoucWenShape& s) noexcept {
  if (s.n == 2.0 && s.sigma == 1.0 && std::fabs(u) <= 1.0)
    return 0.1;  // the paper's shape, fast path
  const double a = std::max(1.0, std::fabs(u));
  const double stiffness = s.n * std::max(1.0, std::fabs(2.0 * s.sigma - 1.0)) *
                           (s.n == 1.0 ? 1.0 : abs_pow(a, s.n - 1.0));
  return std::min(0.1, 0.5 / stiffness);
}

constexpr int kMaxSubsteps = 256;

}  // namespace

double bouc_wen_rate(double z, double ff, double g, const BoucWenShape& s) noexcept {
  const double w = z / ff;
  const double aw = std::fabs(w);
  const auto sgn = [](double v) { return static_cast<double>((v > 0.0) - (v < 0.0)); };
  const double pn1 = s.n == 1.0 ? 1.0 : std::pow(aw, s.n - 1.0);
  return s.theta * g * (1.0 - std::pow(aw, s.n) + s.sigma * pn1 * (sgn(w) - sgn(g)) * w);
}

double advance_bouc_wen_state(double z, double ff, double g, double dt,
                              const BoucWenShape& s) noexcept {
  if (g == 0.0 || !(dt > 0.0) || !(ff > 0.0)) return z;
  const double dir = g > 0.0 ? 1.0 : -1.0;
  const double u0 = dir * z / ff;
  double travel = s.theta * std::fabs(g) * dt / ff;
  double u = u0;
  int steps = 0;
  while (travel > 0.0 && steps < kMaxSubsteps) {
    const double da = std::min(travel, max_step(u, s));
    const double k1 = h(u, s);
    const double k2 = h(u + 0.5 * da * k1, s);
    const double k3 = h(u + 0.5 * da * k2, s);
    const double k4 = h(u + da * k3, s);
    u += da / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    travel -= da;
    ++steps;
  }
  // The exact solution moves monotonically from u0 towards the fixed point 1
  // and never passes it; a travel left after kMaxSubsteps (a gap of seconds)
  // means it has arrived.
  if (travel > 0.0) u = 1.0;
  u = u0 <= 1.0 ? std::clamp(u, u0, 1.0) : std::clamp(u, 1.0, u0);
  return dir * u * ff;
}

}  // namespace tsmh::estimator
