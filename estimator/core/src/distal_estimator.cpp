#include "estimator/distal_estimator.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace tsmh::estimator {

DistalTorqueEstimator::DistalTorqueEstimator(std::unique_ptr<FrictionDynamics> model,
                                             double radius_m, const DifferentiatorConfig& diff,
                                             StartState start)
    : model_(std::move(model)), radius_(radius_m), diff_(diff), start_(start) {
  if (!model_) throw std::invalid_argument("estimator: no friction model");
  if (!(radius_m > 0.0) || !std::isfinite(radius_m))
    throw std::invalid_argument("estimator: radius_m must be a finite number > 0");
}

void DistalTorqueEstimator::reset() noexcept {
  model_->reset();
  diff_.reset();
  started_ = false;
}

Estimate DistalTorqueEstimator::update(double t, double x_in, double tau_in) noexcept {
  if (!std::isfinite(tau_in))
    return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  const Derivatives d = diff_.update(t, x_in);
  if (!d.valid) return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  return finish(t, x_in, d.xd, d.xdd, d.acc_sign, tau_in);
}

Estimate DistalTorqueEstimator::update_exact(double t, double x_in, double xd, double xdd,
                                             double tau_in) noexcept {
  const bool ok = std::isfinite(t) && std::isfinite(x_in) && std::isfinite(xd) &&
                  std::isfinite(xdd) && std::isfinite(tau_in) && (!started_ || t > t_prev_);
  if (!ok) return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  return finish(t, x_in, xd, xdd, sign_of(xdd), tau_in);
}

Estimate DistalTorqueEstimator::finish(double t, double x, double xd, double xdd, double acc_sign,
                                       double tau_in) noexcept {
  const double dt = started_ ? t - t_prev_ : 0.0;
  const Motion m{t, x, xd, xdd, acc_sign, std::fabs(tau_in) / radius_};
  if (!started_ && start_ == StartState::kFreeTip) model_->preset(tau_in / radius_, m);
  started_ = true;
  t_prev_ = t;
  const double f = dt > 0.0 ? model_->step(m, dt) : model_->friction();
  return {xd, xdd, acc_sign, tau_in, f, tau_in - radius_ * f, true, model_->sliding_friction()};
}

}  // namespace tsmh::estimator
