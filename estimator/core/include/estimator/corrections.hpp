#pragma once
// The corrections between the differentiator and the friction model, in one
// place. The differentiator's Kalman channels and the expected sign they
// give are the filter (differentiator.hpp); each correction here adds one
// assumption about the motion that the filter's model does not make, and
// each is kept because it measurably helps on data it was not tuned to
// (docs/friction-model.md, "Corrections"; `scripts/accuracy` regenerates
// the figures in docs/results/corrections.md):
//
// - rest (RestCorrection): a joint whose encoder has not changed for
//   still_time has stopped, so sgn(xdd) is 0;
// - cruise (CruiseCorrection): a stroke after a reversal runs at constant
//   speed, where the true xdd is 0 while the acceleration channel still rings;
// - hindsight (HindsightCorrection): the motion is smooth enough that the
//   fine channel, having seen the next `lag`, knows a sample's acceleration
//   better than the causal estimate did.
//
// CorrectedDifferentiator applies the first two to the differentiator's
// sign (the causal estimate every user of the derivatives gets);
// DistalTorqueEstimator adds the third after each model step.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

#include "estimator/differentiator.hpp"
#include "estimator/friction_model.hpp"
#include "estimator/motion.hpp"

namespace tsmh::estimator {

/// The automatic rest time at kReferenceQuantum, s (CorrectionsConfig::still_time).
inline constexpr double kRestTime = 0.05;

/// The hindsight correction's settings.
struct HindsightConfig {
  /// s after each sample, the fine channel's state extrapolated back gives
  /// that sample's acceleration (0: off). The history holds 59 samples of
  /// lag (59 ms at 1 kHz); at higher rates, or with a longer lag,
  /// a sample is looked at when it is about to leave the history.
  double lag = 0.05;
  /// |xdd| (rad/s^2) where the sign from hindsight starts to count and where
  /// it decides alone (weight clamp((|xdd| - sure) / (certain - sure), 0, 1),
  /// the rest the causal sign); within cruise_armed_time of a manoeuvre, the
  /// `_armed` pair, since the true xdd may be exactly 0.
  double sure = 0.02;
  double certain = 0.05;
  double sure_armed = 0.05;
  double certain_armed = 0.15;
  /// s after a manoeuvre the fine channel's polynomial model rings: no
  /// correction there.
  double guard = 0.3;
  /// After a correction the samples up to this much younger (s) are looked
  /// at in the same pass, so that the corrections around one zero crossing
  /// step the model again once (a cost measure; 0: each at its lag).
  double ahead = 0.005;
};

/// The corrections' settings. Deployed as they are; the accuracy harnesses
/// vary them (online_accuracy's flags, model_accuracy --variants).
struct CorrectionsConfig {
  /// Rest: the encoder has not changed for this long (s): the joint is at
  /// rest and sgn(xdd) is 0 (0: off). Too short and a hand still creeping
  /// into a stop below one count is frozen early; too long and the ringing
  /// after a stop drives the state. Negative (the default): automatic,
  /// kRestTime at kReferenceQuantum, scaled with the cube root of the
  /// encoder quantum: a hand ending a move smoothly (velocity and
  /// acceleration reaching 0 together) covers its last count in a time
  /// proportional to quantum^(1/3). RestCorrection::still_time() gives the
  /// value in use.
  double still_time = -1.0;
  /// Cruise (smooth sign only): after a manoeuvre the acceleration channel's
  /// model cannot follow (its normalised innovation squared, averaged over
  /// 5 ms, above `cruise_nis`), for `cruise_armed_time` s the sign is
  /// weighted by 1 - P(cruise), P(cruise) the probability that the
  /// acceleration and jerk have been exactly 0 over the last `cruise_window`
  /// s (a least-squares cubic through those samples, a Bayes factor against
  /// accelerations and jerks of a moving hand, prior `cruise_prior`).
  /// cruise_window 0: off; the window holds at most 127 samples (at 1 kHz,
  /// any window up to 0.12 s). cruise_prior in (0, 1).
  double cruise_window = 0.04;
  double cruise_prior = 0.1;
  double cruise_nis = 16.0;
  double cruise_armed_time = 1.0;
  /// The cruise test takes the samples' error as this many times the
  /// quantisation variance q^2/12. At constant speed the encoder's error is
  /// not white but a sawtooth that slips by one count every 1 / frac(counts
  /// per sample) samples: as white noise, each slip made the test reject a
  /// true cruise for 20-50 ms and the ringing sign came back.
  double cruise_noise = 5.0;
  HindsightConfig hindsight;
};

/// Rest: an encoder that has not changed for still_time means a joint that
/// has stopped. At rest the true acceleration is exactly 0 and the model's
/// state must not move; the acceleration estimate still rings for a while
/// after a stop (the jerk ends abruptly), so the encoder decides.
class RestCorrection {
 public:
  /// `quantum`: the encoder's, rad (the automatic still_time scales with it).
  RestCorrection(double still_time, double quantum) noexcept;
  void restart(double x) noexcept {
    last_x_ = x;
    still_ = 0.0;
  }
  void observe(double x, double dt) noexcept {
    still_ = x == last_x_ ? still_ + dt : 0.0;
    last_x_ = x;
  }
  bool at_rest() const noexcept { return still_ >= still_time_; }
  /// How long the encoder reading has not changed, s.
  double still_duration() const noexcept { return still_; }
  /// The rest time in use, s (resolved when automatic; 0: off).
  double still_time() const noexcept { return enabled_ ? still_time_ : 0.0; }

 private:
  double still_time_;  // infinity when off: at_rest() is one comparison
  bool enabled_;
  double last_x_ = 0.0;
  double still_ = 0.0;
};

/// Cruise: after a manoeuvre the acceleration channel could not follow, the
/// motion may be a stroke at constant speed, where the true xdd is exactly 0
/// while that channel rings for 0.1-0.2 s. The expected sign is then
/// (1 - P(cruise)) times the sign given motion. On smooth motion the channel
/// stays consistent and the test never runs.
class CruiseCorrection {
 public:
  /// `measurement_variance`: the differentiator's r, rad^2; `enabled`:
  /// cruise_window > 0 and the smooth sign.
  CruiseCorrection(const CorrectionsConfig& config, double measurement_variance, bool enabled);
  bool enabled() const noexcept { return enabled_; }
  /// Starts over at the sample (t, x): nothing seen that the channel could
  /// not follow.
  void restart(double t, double x) noexcept;
  /// The sample (t, x) `dt` after the last, with the acceleration channel's
  /// innovation and its predicted variance there.
  void observe(double t, double x, double innovation, double innovation_var, double dt) noexcept;
  /// Within cruise_armed_time of a manoeuvre: the sign is weighted.
  bool armed() const noexcept { return since_inconsistent_ < armed_time_; }
  /// P(cruise) over the last window (armed only: the window's sums are kept
  /// only then).
  double probability() const noexcept;
  /// Time since the acceleration channel's innovations last exceeded
  /// cruise_nis, s; infinity when off or none yet.
  double time_since_manoeuvre() const noexcept { return since_inconsistent_; }
  double armed_time() const noexcept { return armed_time_; }

 private:
  void add_to_moments(double u, double y, double weight) noexcept;
  void rebuild_moments() noexcept;
  void advance_moments(double dt, double dx) noexcept;

  bool enabled_;
  double window_;
  double inv_window_;
  double prior_;
  double nis_limit_;
  double armed_time_;
  double r_;  // the samples' error variance in the test: cruise_noise r
  // The last samples (a ring, newest at head_), the acceleration channel's
  // normalised innovation squared averaged over 5 ms, and how long ago it
  // last exceeded cruise_nis.
  static constexpr std::size_t kCapacity = 128;
  std::array<double, kCapacity> window_t_{}, window_x_{};
  std::size_t head_ = 0, size_ = 0;
  // Power sums of the samples in the window (see probability()), kept only
  // while armed: how many samples, and samples since the last rebuild.
  std::array<double, 7> moments_{};
  std::array<double, 4> moments_y_{};
  std::size_t count_ = 0;
  int since_rebuild_ = 0;
  bool moments_valid_ = false;
  double nis_ = 1.0;
  double since_inconsistent_ = std::numeric_limits<double>::infinity();
};

/// The differentiator with the rest and cruise corrections applied to its
/// sign: the causal derivatives the estimator steps its model with (and
/// what `tsm fit` differentiates with when asked for the deployed
/// differentiator). Never allocates or throws in update().
class CorrectedDifferentiator {
 public:
  explicit CorrectedDifferentiator(const DifferentiatorConfig& diff = {},
                                   const CorrectionsConfig& corrections = {});
  /// Differentiator::update, the sign corrected. Inline: the estimator's
  /// step then takes the filter's result in registers.
  inline Derivatives update(double t, double x) noexcept;
  void reset() noexcept { filter_.reset(); }

  const Differentiator& filter() const noexcept { return filter_; }
  const RestCorrection& rest() const noexcept { return rest_; }
  const CruiseCorrection& cruise() const noexcept { return cruise_; }
  const CorrectionsConfig& config() const noexcept { return cfg_; }
  /// Whether the last accepted sample (re)started the filters.
  bool restarted() const noexcept { return filter_.restarted(); }

 private:
  CorrectionsConfig cfg_;
  Differentiator filter_;
  RestCorrection rest_;
  CruiseCorrection cruise_;
  double t_ = 0.0;
  double last_sign_ = 0.0;
};

inline Derivatives CorrectedDifferentiator::update(double t, double x) noexcept {
  Derivatives d = filter_.update(t, x);
  if (!d.valid) {
    d.acc_sign = last_sign_;  // the last estimate as it was given
    return d;
  }
  if (filter_.restarted()) {
    rest_.restart(x);
    if (cruise_.enabled()) cruise_.restart(t, x);
  } else {
    const double dt = t - t_;
    if (cruise_.enabled())
      cruise_.observe(t, x, filter_.acceleration_innovation(),
                      filter_.acceleration_innovation_variance(), dt);
    rest_.observe(x, dt);
    if (rest_.at_rest()) {
      d.acc_sign = 0.0;
    } else if (cruise_.armed()) {
      d.acc_sign *= 1.0 - cruise_.probability();
    }
  }
  t_ = t;
  last_sign_ = d.acc_sign;
  return d;
}

/// Hindsight: steps the model again where the fine channel, `lag` later,
/// settles sgn(xdd) differently from the sign the model was given: below
/// |xd| = lambda a sign decided late or wrongly moves the friction state the
/// wrong way, and the error would last until the next saturation (0.3 s and
/// more); this ends it after `lag`. Keeps the last samples as the model was
/// stepped with them (motion and friction) and the model's state every few
/// samples. Never allocates.
///
/// Per sample: next() gives the slot the caller writes the sample's motion
/// into and steps the model with (so the history holds it without a copy),
/// then after_step() records the result and looks back.
class HindsightCorrection {
 public:
  HindsightCorrection() = default;
  /// `enabled`: the caller's model saves its state and reads the sign, and
  /// the differentiator runs the fine channel.
  HindsightCorrection(const HindsightConfig& config, bool enabled);

  bool enabled() const noexcept { return enabled_; }
  /// Empties the history (reset, a restart after a gap): the next sample
  /// goes to slot 0 and is only the state the one after it starts from.
  void forget() noexcept {
    newest_ = kHistory - 1;
    pending_ = -1;
  }
  /// The slot for the motion of the sample the model is about to be stepped
  /// with; after_step() must follow that step.
  Motion& next() noexcept {
    newest_ = (newest_ + 1) % kHistory;
    return history_[newest_].m;
  }
  /// Records the result of the step with next()'s motion (`friction`; the
  /// model holds the state after it), then looks at the samples `lag` old
  /// again with what `diff` has seen since. Returns the newest sample's
  /// friction, corrected when a correction reached it. Inline: on most
  /// samples it only records and finds nothing to correct.
  inline double after_step(double friction, const CorrectedDifferentiator& diff,
                           FrictionDynamics& model) noexcept;
  /// Samples stepped again (the corrected sample and every later one).
  std::size_t resteps() const noexcept { return resteps_; }

 private:
  struct Sample {
    Motion m;
    double friction = 0.0;
  };
  // What a look at one sample found: whether its motion is to be corrected,
  // and how (at rest: no motion; else the sign).
  struct Verdict {
    bool corrected = false;
    bool rest = false;
    double sign = 0.0;
  };
  // What the differentiator has seen by now, for judge().
  struct Seen {
    double still_time, still, since, armed_time;
  };
  static Seen seen(const CorrectedDifferentiator& diff) noexcept {
    return {diff.rest().still_time(), diff.rest().still_duration(),
            diff.cruise().time_since_manoeuvre(), diff.cruise().armed_time()};
  }
  // 64 samples: the deployed lag at 1 kHz and the look-ahead, with the
  // model's state every kStride samples (about 6 kB in all, within a core's
  // first-level cache).
  static constexpr std::size_t kHistory = 64;
  static constexpr std::size_t kStride = 4;
  // A sample is looked at at the latest when this many are pending: the
  // checkpoint before the one before it is still in the history.
  static constexpr std::ptrdiff_t kMaxPending = kHistory - kStride;
  inline Verdict judge(const Sample& s, double back, const Seen& seen,
                       const CorrectedDifferentiator& diff) const noexcept;
  double correct(std::size_t j, const Verdict& v, const CorrectedDifferentiator& diff,
                 FrictionDynamics& model) noexcept;
  bool step_again(std::size_t j, const Motion& m, bool dirty, FrictionDynamics& model) noexcept;
  void catch_up(std::size_t from, FrictionDynamics& model) noexcept;
  std::size_t index_back(std::ptrdiff_t back) const noexcept {
    return (newest_ + kHistory - static_cast<std::size_t>(back)) % kHistory;
  }

  HindsightConfig cfg_;
  bool enabled_ = false;
  double inv_span_ = 0.0, inv_span_armed_ = 0.0;  // 1 / (certain - sure)
  std::array<Sample, kHistory> history_{};
  // The state after the samples at index 0, kStride, 2 kStride, ...; and the
  // newest state while a correction is tried.
  std::array<DynamicsState, kHistory / kStride> checkpoints_{};
  DynamicsState now_{};
  // newest_: the newest sample; the oldest `pending_` of the newest are not
  // yet past lag (-1: the history is empty). The sample before the oldest
  // pending one is kept too: its state is where a correction steps again
  // from.
  std::size_t newest_ = kHistory - 1;
  std::ptrdiff_t pending_ = -1;
  std::size_t resteps_ = 0;
};

// Whether sample s, seen `back` later, was stepped with the wrong sign.
inline HindsightCorrection::Verdict HindsightCorrection::judge(
    const Sample& s, double back, const Seen& seen,
    const CorrectedDifferentiator& diff) const noexcept {
  Verdict v;
  if (seen.still_time > 0.0 && seen.still >= back + seen.still_time) {
    // The encoder has not changed since before this sample: at rest (the
    // rest rule, applied to the samples it now knows were at rest).
    v.corrected = s.m.xd != 0.0 || s.m.xdd != 0.0 || s.m.acc_sign != 0.0;
    v.rest = true;
  } else if (seen.since > back + cfg_.guard) {
    // Close to a manoeuvre the fine channel's polynomial model rings: the
    // causal sign (with the cruise hypothesis) stands.
    const double xdd = diff.filter().fine_acceleration_before(back);
    const double a = std::fabs(xdd);
    const bool armed = seen.since <= back + seen.armed_time;
    const double sure = armed ? cfg_.sure_armed : cfg_.sure;
    if (a > sure) {  // hindsight can tell (a NaN cannot)
      const double w = std::min(1.0, (a - sure) * (armed ? inv_span_armed_ : inv_span_));
      const double hindsight = xdd > 0.0 ? 1.0 : -1.0;
      // A sign within 2 % moves the state too little to matter.
      if (std::fabs(hindsight - s.m.acc_sign) * w >= 0.02) {
        v.sign = w * hindsight + (1.0 - w) * s.m.acc_sign;
        v.corrected = true;
      }
    }
  }
  return v;
}

// The samples `lag` old are looked at again with what the fine channel has
// seen since; the first one whose sign it settles differently goes to
// correct(), which steps the model again (rare: a few samples in a hundred).
// One sample per call (more at a sample rate faster than the history holds).
inline double HindsightCorrection::after_step(double friction, const CorrectedDifferentiator& diff,
                                              FrictionDynamics& model) noexcept {
  history_[newest_].friction = friction;
  // The model's state only every kStride samples: a correction replays the
  // few samples since (the same steps, so the same state bit for bit).
  if (newest_ % kStride == 0) model.save_state(checkpoints_[newest_ / kStride]);
  ++pending_;
  const double t = history_[newest_].m.t;
  while (pending_ > 0) {
    const std::size_t j = index_back(pending_ - 1);
    const Sample& s = history_[j];
    const double back = t - s.m.t;
    if (back < cfg_.lag && pending_ < kMaxPending) break;
    --pending_;
    const Verdict v = judge(s, back, seen(diff), diff);
    if (v.corrected) return correct(j, v, diff, model);
  }
  return friction;
}

}  // namespace tsmh::estimator
