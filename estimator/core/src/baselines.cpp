#include "estimator/baselines.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace tsmh::estimator {
namespace {

bool finite_step(const Motion& m, double dt) {
  return std::isfinite(m.xd) && std::isfinite(m.load) && dt > 0.0 && std::isfinite(dt);
}

void require(bool ok, const std::string& field, const char* why) {
  if (!ok) throw std::invalid_argument(field + ": " + why);
}

}  // namespace

DahlModel::DahlModel(Params p) : BaselineModel(p) {
  require(std::isfinite(p_.sigma0) && p_.sigma0 > 0.0, "params.sigma0", "must be > 0");
  require(std::isfinite(p_.fc) && p_.fc > 0.0, "params.fc", "must be > 0");
}

std::vector<Parameter> DahlModel::parameters() const {
  return {{"params.sigma0", p_.sigma0, 1.0, 1e4, false, "N/rad"},
          {"params.fc", p_.fc, 0.01, 200.0, false, "N"}};
}

double DahlModel::step(const Motion& m, double dt) noexcept {
  if (!finite_step(m, dt) || m.xd == 0.0) return f_;
  const double target = m.xd > 0.0 ? p_.fc : -p_.fc;
  f_ = target + (f_ - target) * std::exp(-p_.sigma0 * std::fabs(m.xd) * dt / p_.fc);
  return f_;
}

LuGreModel::LuGreModel(Params p) : BaselineModel(p) {
  require(std::isfinite(p_.sigma0) && p_.sigma0 > 0.0, "params.sigma0", "must be > 0");
  require(std::isfinite(p_.sigma1) && p_.sigma1 >= 0.0, "params.sigma1", "must be >= 0");
  require(std::isfinite(p_.sigma2) && p_.sigma2 >= 0.0, "params.sigma2", "must be >= 0");
  require(std::isfinite(p_.fc) && p_.fc > 0.0, "params.fc", "must be > 0");
  require(std::isfinite(p_.fs) && p_.fs > 0.0, "params.fs", "must be > 0");
  require(std::isfinite(p_.vs) && p_.vs > 0.0, "params.vs", "must be > 0");
}

std::vector<Parameter> LuGreModel::parameters() const {
  return {{"params.sigma0", p_.sigma0, 1.0, 1e4, false, "N/rad"},
          {"params.sigma1", p_.sigma1, 0.0, 100.0, false, "N s/rad"},
          {"params.sigma2", p_.sigma2, 0.0, 100.0, false, "N s/rad"},
          {"params.fc", p_.fc, 0.01, 200.0, false, "N"},
          {"params.fs", p_.fs, 0.01, 200.0, false, "N"},
          {"params.vs", p_.vs, 1e-3, 10.0, false, "rad/s"}};
}

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

CoulombCapstanModel::CoulombCapstanModel(Params p) : BaselineModel(p) {
  require(std::isfinite(p_.f0) && p_.f0 >= 0.0, "params.f0", "must be >= 0");
  require(std::isfinite(p_.capstan) && p_.capstan >= 0.0 && p_.capstan < 1.0, "params.capstan",
          "must be in [0, 1)");
  require(std::isfinite(p_.v_eps) && p_.v_eps > 0.0, "params.v_eps", "must be > 0");
}

std::vector<Parameter> CoulombCapstanModel::parameters() const {
  return {{"params.f0", p_.f0, 0.0, 200.0, false, "N"},
          {"params.capstan", p_.capstan, 0.0, 0.99, false, ""},
          {"params.v_eps", p_.v_eps, 1e-4, 1.0, false, "rad/s"}};
}

double CoulombCapstanModel::step(const Motion& m, double dt) noexcept {
  if (!finite_step(m, dt)) return f_;
  f_ = std::tanh(m.xd / p_.v_eps) * (p_.f0 + p_.capstan * m.load);
  return f_;
}

}  // namespace tsmh::estimator
