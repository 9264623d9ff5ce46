#include "estimator/baselines.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace tsmh::estimator {
namespace {

bool finite_step(const Motion& m, double dt) {
  return std::isfinite(m.xd) && std::isfinite(m.load) && dt > 0.0 && std::isfinite(dt);
}

// Each baseline's values: name, member, the fit's bounds and unit, the values
// the model accepts (BaselineField).
using DahlValid = DahlModel::Field::Valid;
constexpr DahlModel::Field kDahlFields[] = {
    {"params.sigma0", &DahlParams::sigma0, 1.0, 1e4, "N/rad", DahlValid::kPositive},
    {"params.fc", &DahlParams::fc, 0.01, 200.0, "N", DahlValid::kPositive}};

using LuGreValid = LuGreModel::Field::Valid;
constexpr LuGreModel::Field kLuGreFields[] = {
    {"params.sigma0", &LuGreParams::sigma0, 1.0, 1e4, "N/rad", LuGreValid::kPositive},
    {"params.sigma1", &LuGreParams::sigma1, 0.0, 100.0, "N s/rad", LuGreValid::kNonNegative},
    {"params.sigma2", &LuGreParams::sigma2, 0.0, 100.0, "N s/rad", LuGreValid::kNonNegative},
    {"params.fc", &LuGreParams::fc, 0.01, 200.0, "N", LuGreValid::kPositive},
    {"params.fs", &LuGreParams::fs, 0.01, 200.0, "N", LuGreValid::kPositive},
    {"params.vs", &LuGreParams::vs, 1e-3, 10.0, "rad/s", LuGreValid::kPositive}};

using CapstanValid = CoulombCapstanModel::Field::Valid;
constexpr CoulombCapstanModel::Field kCoulombCapstanFields[] = {
    {"params.f0", &CoulombCapstanParams::f0, 0.0, 200.0, "N", CapstanValid::kNonNegative},
    {"params.capstan", &CoulombCapstanParams::capstan, 0.0, 0.99, "", CapstanValid::kFraction},
    {"params.v_eps", &CoulombCapstanParams::v_eps, 1e-4, 1.0, "rad/s", CapstanValid::kPositive}};

}  // namespace

DahlModel::DahlModel(Params p) : BaselineModel(p, kDahlFields) {}

double DahlModel::step(const Motion& m, double dt) noexcept {
  if (!finite_step(m, dt) || m.xd == 0.0) return f_;
  const double target = m.xd > 0.0 ? p_.fc : -p_.fc;
  f_ = target + (f_ - target) * std::exp(-p_.sigma0 * std::fabs(m.xd) * dt / p_.fc);
  return f_;
}

LuGreModel::LuGreModel(Params p) : BaselineModel(p, kLuGreFields) {}

double LuGreModel::step(const Motion& m, double dt) noexcept {
  if (!finite_step(m, dt)) return f_;
  const double v = m.xd;
  const double r = v / p_.vs;
  const double g = p_.fc + (p_.fs - p_.fc) * std::exp(-r * r);
  const double z0 = z_;
  if (v != 0.0) {
    const double zss = (v > 0.0 ? 1.0 : -1.0) * g / p_.sigma0;
    z_ = zss + (z0 - zss) * std::exp(-p_.sigma0 * std::fabs(v) * dt / g);
  }
  const double zdot = (z_ - z0) / dt;
  f_ = p_.sigma0 * z_ + p_.sigma1 * zdot + p_.sigma2 * v;
  return f_;
}

CoulombCapstanModel::CoulombCapstanModel(Params p) : BaselineModel(p, kCoulombCapstanFields) {}

double CoulombCapstanModel::step(const Motion& m, double dt) noexcept {
  if (!finite_step(m, dt)) return f_;
  f_ = std::tanh(m.xd / p_.v_eps) * (p_.f0 + p_.capstan * m.load);
  return f_;
}

}  // namespace tsmh::estimator
