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
               diff.fine_psd > 0.0 && model_->save_state(probe) &&
               model_->reads_acceleration_sign();
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
  forget_history();
}

void DistalTorqueEstimator::forget_history() noexcept {
  size_ = pending_ = counts_seen_ = repeats_ = crossings_.run = 0;
  stop_known_ = false;
}

// Inline: it runs at nearly every sample in motion, and a call would make
// update() save its registers around it.
[[gnu::always_inline]] inline bool DistalTorqueEstimator::record_crossing(double t,
                                                                          double x_in) noexcept {
  const Motion& last = history_[newest_].m;
  const double direction = x_in > last.x ? 1.0 : -1.0;
  Crossings& c = crossings_;
  if (repeats_ > 0 && last.acc_sign == 0.0) {
    // Leaving a reading the estimator had at rest: a move from rest (a turn
    // still open before the rest is not this run's).
    c.run = 1, c.start_open = diff_.config().settle_starts, c.turn_open = false;
  } else if (direction == c.direction && c.run > 0) {
    ++c.run;
  } else {
    // A turn after two counts or more the old way (not a count flickering).
    c.turn_open = c.run >= 2 && diff_.config().settle_turns;
    c.turn_from = c.t[c.newest];
    c.run = 1, c.start_open = false;
  }
  c.direction = direction;
  stop_known_ = false;
  c.newest = (c.newest + 1) % kCrossings;
  c.t[c.newest] = 0.5 * (last.t + t);
  // A start or turn is settled once its counts span settle_span (at least three).
  return (c.start_open || c.turn_open) && c.run >= 3 &&
         (c.t[c.newest] - c.at(c.run - 1) >= diff_.config().settle_span || c.run == kCrossings);
}

Estimate DistalTorqueEstimator::update(double t, double x_in, double tau_in,
                                       double tension) noexcept {
  if (!std::isfinite(tau_in))
    return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  const Derivatives d = diff_.update(t, x_in);
  if (!d.valid) return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  // A gap that restarts the differentiator breaks the history as well.
  const bool restart = diff_.restarted();
  Estimate e = finish(t, x_in, d.xd, d.xdd, d.acc_sign, tau_in, tension);
  if (!hindsight_) return e;
  if (restart) forget_history();
  // The encoder moves again after standing still for two samples or more:
  // settle_reversal() looks at that stretch (in motion it moves every
  // sample or two, and this costs a comparison).
  bool settle = false;
  bool start = false;  // settle_start() is due
  if (counts_seen_ > 0 && x_in == counts_[0]) {
    ++repeats_;
  } else {
    const DifferentiatorConfig& c = diff_.config();
    settle = repeats_ > 0 && c.settle_reversals;
    if (size_ > 0) start = record_crossing(t, x_in);
    counts_ = {x_in, counts_[0], counts_[1], counts_[2]};
    counts_seen_ = std::min<std::size_t>(counts_seen_ + 1, 4);
    repeats_ = 0;
  }
  newest_ = size_ == 0 ? 0 : (newest_ + 1) % kHistory;
  Sample& s = history_[newest_];
  s.m = Motion{t,      x_in, d.xd, d.xdd, d.acc_sign, std::fabs(tau_in) / radius_, tau_in / radius_,
               tension};
  s.friction = e.friction;
  s.settled = false;
  model_->save_state(s.state);
  size_ = std::min(size_ + 1, kHistory);
  if (size_ > 1) ++pending_;
  if (settle) settle_reversal();
  if (start) crossings_.start_open ? settle_start() : settle_turn();
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
  // The estimated stop of a move running out (settle_stops): once per
  // still stretch, when its first sample is looked at as one at rest.
  const auto stop_time = [&] {
    if (!stop_known_) stop_ = estimated_stop(), stop_known_ = true;
    return stop_;
  };
  bool touched = false;  // the model left the newest state
  bool dirty = false;    // the samples after `frontier` are to be stepped again
  std::size_t frontier = 0;
  while (pending_ > 0) {
    const std::size_t j = index_back(pending_ - 1);
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
      // settle_reversal() or settle_start() decided it
    } else if (still_time > 0.0 && diff_.still_duration() >= back + still_time) {
      // The encoder has not changed since before this sample: at rest;
      // unless a move running out stops after it (settle_stops: its last
      // count came more than still_time before its stop), then decelerating.
      const double sign = c.settle_stops && s.m.t < stop_time() ? -crossings_.direction : 0.0;
      corrected = m.xd != 0.0 || m.xdd != 0.0 || m.acc_sign != sign;
      m.xd = m.xdd = 0.0;
      m.acc_sign = sign;
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
  const double after = counts_[0] > counts_[1] ? 1.0 : -1.0;
  // Came the other way over the two counts before (a move, not a flicker).
  if ((counts_[1] > counts_[2] ? 1.0 : -1.0) == after ||
      (counts_[2] > counts_[3] ? 1.0 : -1.0) == after)
    return;
  // The stretch: samples 1 .. n back at counts_[1].
  std::size_t n = 1;
  const std::size_t span = std::min(size_, kReversalSpan);
  while (n + 1 < span && sample_back(n + 1).m.x == counts_[1])
    ++n;
  if (n + 1 >= span) return;  // its start is no longer held, or a hold
  std::size_t first = 0;      // back of the oldest sample whose sign changes
  for (std::size_t b = n; b >= 1; --b) {
    Sample& s = sample_back(b);
    if (s.m.acc_sign != 0.0) continue;
    s.m.acc_sign = after;
    s.settled = true;
    if (first == 0) first = b;
  }
  if (first > 0) step_again_from(first);
}

// From rest at constant jerk (a hand starting a reach, or running out
// into a hold) the velocity grows as the square of the time since the
// start (until the stop), so r = sqrt(1 / interval), the square root of an
// interval's mean velocity in counts, falls on a line through zero there.
namespace {
// The time the line fitted to the intervals between `n` count times `c`
// (oldest first) reaches r = 0: weighted least squares, each interval's r
// at its midpoint, weight interval^2 (the sample clock's +-0.5 ms on a
// count time is a larger part of a short interval). `rising`: r must grow
// (a start), else fall (a stop); NaN when it does not.
double zero_of_root_velocity(const double* c, std::size_t n, bool rising) noexcept {
  const double ref = c[n - 1];
  double sw = 0.0, sm = 0.0, sr = 0.0, smm = 0.0, smr = 0.0;
  for (std::size_t k = 0; k + 1 < n; ++k) {
    const double d = c[k + 1] - c[k], w = d * d, m = 0.5 * (c[k] + c[k + 1]) - ref;
    const double r = std::sqrt(1.0 / d);
    sw += w, sm += w * m, sr += w * r, smm += w * m * m, smr += w * m * r;
  }
  const double det = sw * smm - sm * sm;
  if (!(det > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double slope = (sw * smr - sm * sr) / det, r0 = (sr - slope * sm) / sw;
  if (rising ? !(slope > 0.0) : !(slope < 0.0)) return std::numeric_limits<double>::quiet_NaN();
  return ref - r0 / slope;
}
}  // namespace

double DistalTorqueEstimator::estimated_stop() const noexcept {
  const Crossings& c = crossings_;
  if (c.run < 3) return std::numeric_limits<double>::quiet_NaN();
  const double last = c.t[c.newest], span = diff_.config().settle_span;
  std::size_t n = 3;
  while (n < std::min(c.run, kCrossings) && last - c.at(n) <= span)
    ++n;
  const std::array<double, kCrossings> times = c.oldest_first(n);
  const double stop = zero_of_root_velocity(times.data(), n, false);
  if (std::isnan(stop)) return stop;
  // The same bound as for a start, the other way.
  return std::min(stop, last + 2.5 * (last - times[n - 3]));
}

// A move from rest has shown counts over settle_span (record_crossing()):
// its start t0 is estimated from their timing, and the samples before its
// first count back to t0 that the estimator had at rest get the move's
// sign (those the hindsight has given it already keep theirs; one with the
// other sign ends the stretch). The model is then stepped again from the
// first of them to now.
[[gnu::noinline]] void DistalTorqueEstimator::settle_start() noexcept {
  Crossings& c = crossings_;
  c.start_open = false;
  const std::array<double, kCrossings> times = c.oldest_first(c.run);
  const double t_first = times[0], direction = c.direction;
  // At constant jerk the first count comes at most 2.3 (t3 - t1) after
  // the start (the reading at rest a whole count from the first change).
  double t0 = zero_of_root_velocity(times.data(), c.run, true);
  if (std::isnan(t0)) return;
  t0 = std::max(t0, t_first - 2.5 * (times[2] - t_first));
  std::size_t b = 1;  // back to the last sample before the first count
  while (b + 1 < size_ && sample_back(b).m.t > t_first)
    ++b;
  std::size_t first = 0;  // back of the oldest sample whose sign changes
  for (; b + 1 < size_; ++b) {
    Sample& s = sample_back(b);
    if (s.m.t < t0 || s.m.acc_sign * direction < 0.0) break;
    if (s.m.acc_sign != 0.0) continue;
    s.m.acc_sign = direction;
    s.settled = true;
    first = b;
  }
  if (first > 0) step_again_from(first);
}

// A run of counts from a turn has spanned settle_span (record_crossing()):
// if they speed up, the joint accelerated out of the turn, and decelerated
// into it. From the old way's last count to now the acceleration had the
// new way's sign; the samples there that the fine channel could not
// correct (within hindsight_guard after a manoeuvre, where look_back()
// leaves the causal sign) get it, unless at rest.
[[gnu::noinline]] void DistalTorqueEstimator::settle_turn() noexcept {
  Crossings& c = crossings_;
  c.turn_open = false;
  const std::array<double, kCrossings> times = c.oldest_first(c.run);
  if (std::isnan(zero_of_root_velocity(times.data(), c.run, true))) return;
  const double direction = c.direction, t_now = history_[newest_].m.t;
  const double since = diff_.time_since_manoeuvre(), guard = diff_.config().hindsight_guard;
  std::size_t first = 0;
  for (std::size_t b = 1; b + 1 < size_ && sample_back(b).m.t >= c.turn_from; ++b) {
    Sample& s = sample_back(b);
    if (since > t_now - s.m.t + guard) break;  // the fine channel's to correct
    if (s.m.acc_sign * direction >= 1.0 || (s.m.acc_sign == 0.0 && s.m.xd == 0.0)) continue;
    s.m.acc_sign = direction;
    s.settled = true;
    first = b;
  }
  if (first > 0) step_again_from(first);
}

// The samples `back` and younger were given new signs: steps the model
// again from `back` to now.
void DistalTorqueEstimator::step_again_from(std::size_t back) noexcept {
  const std::size_t j = index_back(back);
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
                                             double tau_in, double tension) noexcept {
  const bool ok = std::isfinite(t) && std::isfinite(x_in) && std::isfinite(xd) &&
                  std::isfinite(xdd) && std::isfinite(tau_in) && (!started_ || t > t_prev_);
  if (!ok) return Estimate{.tau_out_est = std::numeric_limits<double>::quiet_NaN()};
  return finish(t, x_in, xd, xdd, sign_of(xdd), tau_in, tension);
}

[[gnu::always_inline]] inline Estimate DistalTorqueEstimator::finish(double t, double x, double xd,
                                                                     double xdd, double acc_sign,
                                                                     double tau_in,
                                                                     double tension) noexcept {
  const double dt = started_ ? t - t_prev_ : 0.0;
  const Motion m{t, x, xd, xdd, acc_sign, std::fabs(tau_in) / radius_, tau_in / radius_, tension};
  if (!started_ && start_ == StartState::kFreeTip) model_->preset(tau_in / radius_, m);
  started_ = true;
  t_prev_ = t;
  const double f = dt > 0.0 ? model_->step(m, dt) : model_->friction();
  return {xd,     xdd, acc_sign, tau_in, f, tau_in - radius_ * f, true, model_->sliding_friction(),
          tension};
}

}  // namespace tsmh::estimator
