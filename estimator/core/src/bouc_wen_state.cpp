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

// Largest RK4 step: kMaxRk4Travel in normalised travel, and less where the state is far beyond Ff
// so that the local stiffness |dh/du| * step stays <= 0.5, far inside RK4's stability region.
double max_step(double u, const BoucWenShape& s) noexcept {
  if (s.n == 2.0 && s.sigma == 1.0 && std::fabs(u) <= 1.0)
    return kMaxRk4Travel;  // the paper's shape
  const double a = std::max(1.0, std::fabs(u));
  const double stiffness = s.n * std::max(1.0, std::fabs(2.0 * s.sigma - 1.0)) *
                           (s.n == 1.0 ? 1.0 : abs_pow(a, s.n - 1.0));
  return std::min(kMaxRk4Travel, 0.5 / stiffness);
}

constexpr int kMaxSubsteps = 256;

// Exact solution of du/da = h(u) over `travel` for n = 1 and n = 2 (any
// sigma >= 1/2), used when the travel would need several RK4 sub-steps
// (stiff parameters during identification, dropped samples): its cost does
// not grow with the travel. Unloading (u < 0) runs until u = 0, then loading.
//   n = 2: u < 0: u' = 1 + k u^2, k = 2 sigma - 1: u = tan(r a + atan(r u0)) / r, r = sqrt(k)
//          u >= 0: u' = 1 - u^2: u = tanh(a + atanh(u0)) (coth beyond the fixed point)
//   n = 1: u < 0: u' = 1 - k u: u = (1 - (1 - k u0) e^(-k a)) / k
//          u >= 0: u' = 1 - u: u = 1 - (1 - u0) e^(-a)
bool closed_form(double u0, double travel, const BoucWenShape& s, double& u) {
  if (s.n != 1.0 && s.n != 2.0) return false;
  const double k = 2.0 * s.sigma - 1.0;
  u = u0;
  double left = travel;
  if (u < 0.0) {
    double to_zero = 0.0;  // travel until u = 0
    if (k <= 1e-12) {
      to_zero = -u;
    } else if (s.n == 2.0) {
      to_zero = std::atan(std::sqrt(k) * -u) / std::sqrt(k);
    } else {
      to_zero = std::log1p(k * -u) / k;
    }
    if (left < to_zero) {
      if (k <= 1e-12) {
        u += left;
      } else if (s.n == 2.0) {
        const double r = std::sqrt(k);
        u = std::tan(r * left + std::atan(r * u)) / r;
      } else {
        u = (1.0 - (1.0 - k * u) * std::exp(-k * left)) / k;
      }
      u = std::min(u, 0.0);
      return true;
    }
    left -= to_zero;
    u = 0.0;
  }
  if (s.n == 1.0) {
    u = 1.0 - (1.0 - u) * std::exp(-left);
  } else if (u < 1.0) {
    u = std::tanh(left + std::atanh(u));
  } else if (u > 1.0) {
    u = 1.0 / std::tanh(left + std::atanh(1.0 / u));
  }
  return true;
}

}  // namespace

double bouc_wen_rate(double z, double ff, double g, const BoucWenShape& s) noexcept {
  const double w = z / ff;
  const double aw = std::fabs(w);
  const auto sgn = [](double v) { return static_cast<double>((v > 0.0) - (v < 0.0)); };
  const double pn1 = s.n == 1.0 ? 1.0 : std::pow(aw, s.n - 1.0);
  return s.theta * g * (1.0 - std::pow(aw, s.n) + s.sigma * pn1 * (sgn(w) - sgn(g)) * w);
}

double advance_bouc_wen_state_general(double z, double ff, double g, double dt,
                                      const BoucWenShape& s) noexcept {
  if (g == 0.0 || !(dt > 0.0) || !(ff > 0.0)) return z;
  const double dir = g > 0.0 ? 1.0 : -1.0;
  const double u0 = dir * z / ff;
  double travel = s.theta * std::fabs(g) * dt / ff;
  double u = u0;
  int steps = 0;
  // One RK4 step covers the usual 1 kHz sample; longer travels take the
  // exact solution where there is one.
  if (travel > max_step(u0, s) && closed_form(u0, travel, s, u)) travel = 0.0;
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
