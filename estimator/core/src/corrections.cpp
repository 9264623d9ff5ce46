#include "estimator/corrections.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "estimator/differentiator.hpp"

namespace tsmh::estimator {

HindsightCorrection::HindsightCorrection(const HindsightConfig& config, bool enabled)
    : cfg_(config), enabled_(enabled && config.lag > 0.0) {
  // certain <= sure: a step at `sure` (the weight is 1 beyond it).
  const auto inverse_span = [](double sure, double certain) {
    return certain > sure ? 1.0 / (certain - sure) : std::numeric_limits<double>::infinity();
  };
  inv_span_ = inverse_span(config.sure, config.certain);
  inv_span_armed_ = inverse_span(config.sure_armed, config.certain_armed);
}

// The samples `lag` old are looked at again with what the fine channel has
// seen since: where that settles sgn(xdd) differently, the model steps that
// sample again from the state before it, and every sample after it, to now.
// One sample per call (more at a sample rate faster than the history holds);
// after a correction, also those up to `ahead` younger, so that one pass to
// now serves them all.
double HindsightCorrection::update(const Motion& newest, double friction,
                                   const Differentiator& diff, FrictionDynamics& model) noexcept {
  newest_ = size_ == 0 ? 0 : (newest_ + 1) % kHistory;
  Sample& s_new = history_[newest_];
  s_new.m = newest;
  s_new.friction = friction;
  model.save_state(s_new.state);
  size_ = std::min(size_ + 1, kHistory);
  if (size_ > 1) ++pending_;

  const double t = newest.t;
  const double still_time = diff.still_time();
  bool touched = false;  // the model left the newest state
  bool dirty = false;    // the samples after `frontier` are to be stepped again
  std::size_t frontier = 0;
  while (pending_ > 0) {
    const std::size_t j = index_back(pending_ - 1);
    const Sample& s = history_[j];
    const double back = t - s.m.t;
    if (back < cfg_.lag && pending_ < kHistory - 1 && !(dirty && back >= cfg_.lag - cfg_.ahead))
      break;
    --pending_;
    Motion m = s.m;
    bool corrected = false;
    if (still_time > 0.0 && diff.still_duration() >= back + still_time) {
      // The encoder has not changed since before this sample: at rest (the
      // rest rule, applied to the samples it now knows were at rest).
      corrected = m.xd != 0.0 || m.xdd != 0.0 || m.acc_sign != 0.0;
      m.xd = m.xdd = m.acc_sign = 0.0;
    } else {
      // Close to a manoeuvre the fine channel's polynomial model rings: the
      // causal sign (with the cruise hypothesis) stands.
      const double since = diff.time_since_manoeuvre();
      if (since > back + cfg_.guard) {
        const double xdd = diff.fine_acceleration_before(back);
        const double a = std::fabs(xdd);
        const bool armed = since <= back + diff.config().cruise_armed_time;
        const double sure = armed ? cfg_.sure_armed : cfg_.sure;
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
    dirty = step_again(j, m, dirty, model) || dirty;
    frontier = j;
  }
  if (dirty) {
    catch_up(frontier, model);  // the model ends at the newest sample
  } else if (touched) {
    model.restore_state(history_[newest_].state);
  }
  return history_[newest_].friction;
}

// Steps sample j again with the motion m from the state before it (on the
// corrected path when `dirty`): true when that changed its friction, so that
// the samples after it must be stepped again. Out of line: rare, and the
// per-sample decision above stays compact.
[[gnu::noinline]] bool HindsightCorrection::step_again(std::size_t j, const Motion& m, bool dirty,
                                                       FrictionDynamics& model) noexcept {
  Sample& s = history_[j];
  const Sample& before = history_[(j + kHistory - 1) % kHistory];
  model.restore_state(before.state);
  // The interval as the estimator formed it: this sample's time less the last one's.
  const double f = model.step(m, m.t - before.m.t);
  const double level = model.sliding_friction();
  const double tolerance = 1e-4 * (std::isfinite(level) ? std::max(level, 1.0) : 1.0);
  const bool changed = std::fabs(f - s.friction) > tolerance;
  // A correction too small to matter on the uncorrected path is dropped.
  if (!changed && !dirty) return false;
  s.m = m;
  s.friction = f;
  model.save_state(s.state);
  ++resteps_;
  return changed;
}

// Steps every sample after `from` to the newest again, from the state the
// model holds (from's): the model then holds the corrected newest state.
[[gnu::noinline]] void HindsightCorrection::catch_up(std::size_t from,
                                                     FrictionDynamics& model) noexcept {
  for (std::size_t k = (from + 1) % kHistory; k != (newest_ + 1) % kHistory;
       k = (k + 1) % kHistory) {
    Sample& later = history_[k];
    const double t_before = history_[(k + kHistory - 1) % kHistory].m.t;
    later.friction = model.step(later.m, later.m.t - t_before);
    model.save_state(later.state);
    ++resteps_;
  }
}

}  // namespace tsmh::estimator
