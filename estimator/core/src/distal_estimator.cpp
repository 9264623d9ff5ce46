#include "estimator/distal_estimator.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace tsmh::estimator {

namespace {
constexpr double kUnknown = std::numeric_limits<double>::quiet_NaN();
// An encoder that reads Inf is as good as none.
double known(double v) noexcept {
  return std::isfinite(v) ? v : kUnknown;
}
bool hindsight_possible(const DifferentiatorConfig& diff, const FrictionDynamics* model) {
  DynamicsState probe;
  return model != nullptr && diff.sign_mode == SignMode::kSmooth && diff.fine_psd > 0.0 &&
         model->save_state(probe) && model->reads_acceleration_sign();
}
// Every correction acts on sgn(xdd) alone: for a model that never reads it
// they would change nothing the model computes, and cost a step's worth of
// bookkeeping, so they stay off.
CorrectionsConfig corrections_for(const FrictionDynamics* model, CorrectionsConfig c) {
  if (model != nullptr && !model->reads_acceleration_sign()) {
    c.still_time = 0.0;
    c.cruise_window = 0.0;
  }
  return c;
}
}  // namespace

DistalTorqueEstimator::DistalTorqueEstimator(std::unique_ptr<FrictionDynamics> model,
                                             double radius_m, const DifferentiatorConfig& diff,
                                             StartState start, const CorrectionsConfig& corrections)
    : model_(std::move(model)),
      radius_(radius_m),
      diff_(diff, corrections_for(model_.get(), corrections)),
      start_(start),
      hindsight_(corrections.hindsight, hindsight_possible(diff, model_.get())) {
  if (!model_) throw std::invalid_argument("estimator: no friction model");
  if (!(radius_m > 0.0) || !std::isfinite(radius_m))
    throw std::invalid_argument("estimator: radius_m must be a finite number > 0");
}

void DistalTorqueEstimator::reset() noexcept {
  model_->reset();
  diff_.reset();
  started_ = false;
  hindsight_.forget();
}

Estimate DistalTorqueEstimator::update(double t, double x_in, double tau_in, double tension,
                                       double x_out) noexcept {
  if (!std::isfinite(tau_in))
    return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  const Derivatives d = diff_.update(t, x_in);
  if (!d.valid) return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  const double load = std::fabs(tau_in) / radius_, drive = tau_in / radius_;
  if (!hindsight_.enabled()) {
    const Motion m{.t = t,
                   .x = x_in,
                   .xd = d.xd,
                   .xdd = d.xdd,
                   .acc_sign = d.acc_sign,
                   .load = load,
                   .drive = drive,
                   .tension = tension,
                   .x_out = known(x_out)};
    return finish(m, d.xdd, tau_in);
  }
  // A gap that restarts the differentiator breaks the history as well.
  if (diff_.restarted()) hindsight_.forget();
  // The model steps with the motion where the history keeps it: no copy.
  Motion& m = hindsight_.next();
  m.t = t;
  m.x = x_in;
  m.xd = d.xd;
  m.xdd = d.xdd;
  m.acc_sign = d.acc_sign;
  m.load = load;
  m.drive = drive;
  m.tension = tension;
  m.distal = kUnknown;
  m.x_out = known(x_out);
  Estimate e = finish(m, d.xdd, tau_in);
  const double f = hindsight_.after_step(e.friction, diff_, *model_);
  if (f != e.friction) {
    e.friction = f;
    e.tau_out_est = tau_in - radius_ * f;
    e.friction_level = model_->sliding_friction();
  }
  return e;
}

Estimate DistalTorqueEstimator::update_exact(double t, double x_in, double xd, double xdd,
                                             double tau_in, double tension, double x_out) noexcept {
  const bool ok = std::isfinite(t) && std::isfinite(x_in) && std::isfinite(xd) &&
                  std::isfinite(xdd) && std::isfinite(tau_in) && (!started_ || t > t_prev_);
  if (!ok) return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  const Motion m{.t = t,
                 .x = x_in,
                 .xd = xd,
                 .xdd = xdd,
                 .acc_sign = sign_of(xdd),
                 .load = std::fabs(tau_in) / radius_,
                 .drive = tau_in / radius_,
                 .tension = tension,
                 .x_out = known(x_out)};
  return finish(m, xdd, tau_in);
}

[[gnu::always_inline]] inline Estimate DistalTorqueEstimator::finish(const Motion& m, double xdd,
                                                                     double tau_in) noexcept {
  const double dt = started_ ? m.t - t_prev_ : 0.0;
  if (!started_ && start_ == StartState::kFreeTip) model_->preset(tau_in / radius_, m);
  started_ = true;
  t_prev_ = m.t;
  // One virtual call: the friction and the sliding level together.
  const FrictionDynamics::StepResult s =
      dt > 0.0 ? model_->step_with_level(m, dt)
               : FrictionDynamics::StepResult{model_->friction(), model_->sliding_friction()};
  return {m.xd,       xdd,
          m.acc_sign, tau_in,
          s.friction, tau_in - radius_ * s.friction,
          true,       s.sliding_friction,
          m.tension};
}

}  // namespace tsmh::estimator
