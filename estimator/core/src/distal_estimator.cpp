#include "estimator/distal_estimator.hpp"

#include <algorithm>
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
  DynamicsState probe;
  hindsight_ = diff.hindsight_lag > 0.0 && diff.sign_mode == SignMode::kSmooth &&
               diff.fine_psd > 0.0 && model_->save_state(probe);
  // certain <= sure: a step at `sure` (the weight is 1 beyond it).
  const auto inverse_span = [](double sure, double certain) {
    return certain > sure ? 1.0 / (certain - sure) : std::numeric_limits<double>::infinity();
  };
  inv_span_ = inverse_span(diff.hindsight_sure, diff.hindsight_certain);
  inv_span_armed_ = inverse_span(diff.hindsight_sure_armed, diff.hindsight_certain_armed);
}

void DistalTorqueEstimator::reset() noexcept {
  model_->reset();
  diff_.reset();
  started_ = false;
  size_ = pending_ = counts_seen_ = repeats_ = 0;
}

Estimate DistalTorqueEstimator::update(double t, double x_in, double tau_in) noexcept {
  if (!std::isfinite(tau_in))
    return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  const Derivatives d = diff_.update(t, x_in);
  if (!d.valid) return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  // A gap that restarts the differentiator breaks the history as well.
  const bool restart = diff_.restarted();
  Estimate e = finish(t, x_in, d.xd, d.xdd, d.acc_sign, tau_in);
  if (!hindsight_) return e;
  if (restart) size_ = pending_ = counts_seen_ = repeats_ = 0;
  // The encoder moves again after standing still for two samples or more:
  // settle_reversal() looks at that stretch (in motion it moves every
  // sample or two, and this costs a comparison).
  bool settle = false;
  if (counts_seen_ > 0 && x_in == counts_[0]) {
    ++repeats_;
  } else {
    settle = repeats_ > 0 && diff_.config().settle_reversals;
    counts_ = {x_in, counts_[0], counts_[1], counts_[2]};
    counts_seen_ = std::min<std::size_t>(counts_seen_ + 1, 4);
    repeats_ = 0;
  }
  newest_ = size_ == 0 ? 0 : (newest_ + 1) % kHistory;
  Sample& s = history_[newest_];
  s.m = Motion{t, x_in, d.xd, d.xdd, d.acc_sign, std::fabs(tau_in) / radius_};
  s.friction = e.friction;
  s.settled = false;
  model_->save_state(s.state);
  size_ = std::min(size_ + 1, kHistory);
  if (size_ > 1) ++pending_;
  if (settle) settle_reversal();
  look_back(t);
  if (s.friction != e.friction) {
    e.friction = s.friction;
    e.tau_out_est = tau_in - radius_ * s.friction;
    e.friction_level = model_->sliding_friction();
  }
  return e;
}

// The samples hindsight_lag old are looked at again with what the fine
// channel has seen since: where that settles sgn(xdd) differently, the model
// steps that sample again from the state before it, and every sample after
// it, to now. The causal sign decided late or wrongly around a zero crossing
// of the acceleration; its effect on the friction state would otherwise last
// until the next saturation (0.3 s and more at low speed). One sample per
// call (more at a faster sample rate than the history holds); after a
// correction, also those up to hindsight_ahead younger, so that one pass
// to now serves them all.
void DistalTorqueEstimator::look_back(double t) noexcept {
  const DifferentiatorConfig& c = diff_.config();
  bool touched = false;  // the model left the newest state
  bool dirty = false;    // the samples after `frontier` are to be stepped again
  std::size_t frontier = 0;
  while (pending_ > 0) {
    const std::size_t j = (newest_ + kHistory - (pending_ - 1)) % kHistory;
    Sample& s = history_[j];
    const double back = t - s.m.t;
    if (back < c.hindsight_lag && pending_ < kHistory - 1 &&
        !(dirty && back >= c.hindsight_lag - c.hindsight_ahead))
      break;
    --pending_;
    Motion m = s.m;
    bool corrected = false;
    const double still_time = diff_.still_time();
    if (s.settled) {
      // settle_reversal() decided it
    } else if (still_time > 0.0 && diff_.still_duration() >= back + still_time) {
      // The encoder has not changed since before this sample: at rest.
      corrected = m.xd != 0.0 || m.xdd != 0.0 || m.acc_sign != 0.0;
      m.xd = m.xdd = m.acc_sign = 0.0;
    } else {
      // Close to a manoeuvre the fine channel's polynomial model rings: the
      // causal sign (with the cruise hypothesis) stands.
      const double since = diff_.time_since_manoeuvre();
      if (since > back + c.hindsight_guard) {
        const double xdd = diff_.fine_acceleration_before(back);
        const double a = std::fabs(xdd);
        const bool armed = since <= back + c.cruise_armed_time;
        const double sure = armed ? c.hindsight_sure_armed : c.hindsight_sure;
        if (a > sure) {  // hindsight can tell (a NaN cannot)
          const double w = std::min(1.0, (a - sure) * (armed ? inv_span_armed_ : inv_span_));
          const double sign = xdd > 0.0 ? 1.0 : -1.0;
          // A sign within 2 % moves the state too little to matter.
          if (std::fabs(sign - s.m.acc_sign) * w >= 0.02) {
            m.acc_sign = w * sign + (1.0 - w) * s.m.acc_sign;
            corrected = true;
          }
        }
      }
    }
    if (!corrected && !dirty) continue;
    // While dirty, every sample is stepped again from the corrected path.
    touched = true;
    dirty = step_again(j, m, dirty) || dirty;
    frontier = j;
  }
  if (dirty) {
    catch_up(frontier);  // the model ends at the newest sample
  } else if (touched) {
    model_->restore_state(history_[newest_].state);
  }
}

// When the encoder moves again after standing still for at least two
// samples, and moves back the way it came (after two counts the other way:
// a move, not a count flickering), the joint reversed in that stretch: its
// velocity went from one sign to the other, so on the whole its
// acceleration had the new direction's sign there, however small. Where
// the estimator had declared rest (sign 0; the fine channel's
// extrapolation resolves only accelerations of a few hundredths of a
// rad/s^2), eq. (4) drove the true state with lambda sgn(xdd) all that
// time. Those samples get the new direction's sign and the model is
// stepped again from the first of them to now. Samples with a sign of
// their own keep it: the acceleration may have turned again before the
// encoder showed the reversal (a dip: two reversals in quick succession).
// update() calls it when the newest sample, counts_[0], left a reading,
// counts_[1], that the samples before it had repeated.
[[gnu::noinline]] void DistalTorqueEstimator::settle_reversal() noexcept {
  // Four readings seen since the (re)start: as many samples in the history.
  if (counts_seen_ < 4) return;
  const auto at = [&](std::size_t back) -> Sample& {
    return history_[(newest_ + kHistory - back) % kHistory];
  };
  const double after = counts_[0] > counts_[1] ? 1.0 : -1.0;
  // Came the other way over the two counts before (a move, not a flicker).
  if ((counts_[1] > counts_[2] ? 1.0 : -1.0) == after ||
      (counts_[2] > counts_[3] ? 1.0 : -1.0) == after)
    return;
  // The stretch: samples 1 .. n back at counts_[1].
  std::size_t n = 1;
  while (n + 1 < size_ && at(n + 1).m.x == counts_[1])
    ++n;
  if (n + 1 >= size_) return;  // its start is no longer held
  std::size_t first = 0;       // back of the oldest sample whose sign changes
  for (std::size_t b = n; b >= 1; --b) {
    Sample& s = at(b);
    if (s.m.acc_sign != 0.0) continue;
    s.m.acc_sign = after;
    s.settled = true;
    if (first == 0) first = b;
  }
  if (first == 0) return;
  const std::size_t j = (newest_ + kHistory - first) % kHistory;
  Motion m = history_[j].m;
  step_again(j, m, true);
  catch_up(j);
}

// Out of line: rare, and the per-sample decision above stays compact.
[[gnu::noinline]] bool DistalTorqueEstimator::step_again(std::size_t j, const Motion& m,
                                                         bool dirty) noexcept {
  Sample& s = history_[j];
  const Sample& before = history_[(j + kHistory - 1) % kHistory];
  model_->restore_state(before.state);
  // The interval as finish() formed it: this sample's time less the last one's.
  const double f = model_->step(m, m.t - before.m.t);
  const double level = model_->sliding_friction();
  const double tolerance = 1e-4 * (std::isfinite(level) ? std::max(level, 1.0) : 1.0);
  const bool changed = std::fabs(f - s.friction) > tolerance;
  // A correction too small to matter on the uncorrected path is dropped.
  if (!changed && !dirty) return false;
  s.m = m;
  s.friction = f;
  model_->save_state(s.state);
  ++resteps_;
  return changed;
}

[[gnu::noinline]] void DistalTorqueEstimator::catch_up(std::size_t from) noexcept {
  for (std::size_t k = (from + 1) % kHistory; k != (newest_ + 1) % kHistory;
       k = (k + 1) % kHistory) {
    Sample& later = history_[k];
    const double t_before = history_[(k + kHistory - 1) % kHistory].m.t;
    later.friction = model_->step(later.m, later.m.t - t_before);
    model_->save_state(later.state);
    ++resteps_;
  }
}

Estimate DistalTorqueEstimator::update_exact(double t, double x_in, double xd, double xdd,
                                             double tau_in) noexcept {
  const bool ok = std::isfinite(t) && std::isfinite(x_in) && std::isfinite(xd) &&
                  std::isfinite(xdd) && std::isfinite(tau_in) && (!started_ || t > t_prev_);
  if (!ok) return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  return finish(t, x_in, xd, xdd, sign_of(xdd), tau_in);
}

[[gnu::always_inline]] inline Estimate DistalTorqueEstimator::finish(double t, double x, double xd,
                                                                     double xdd, double acc_sign,
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
