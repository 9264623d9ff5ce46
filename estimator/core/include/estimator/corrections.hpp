#pragma once
// The corrections between the differentiator and the friction model. Each is
// kept because it measurably helps on data it was not tuned to
// (docs/friction-model.md, "Corrections", has the figures; `scripts/accuracy`
// regenerates them in docs/results/corrections.md). The differentiator's
// Kalman channels and its expected sign are the filter; each correction
// adds one assumption about the motion that the filter's model does not make:
//
// - rest (DifferentiatorConfig::still_time, applied to the causal sign in
//   the differentiator and here in hindsight): a joint whose encoder has not
//   changed for still_time has stopped, so sgn(xdd) is 0;
// - cruise (DifferentiatorConfig::cruise_window, in the differentiator's
//   sign): a stroke after a reversal runs at constant speed, where the true
//   xdd is 0 while the acceleration channel still rings;
// - hindsight (HindsightCorrection, here): the motion is smooth enough that
//   the fine channel, having seen the next `lag`, knows a sample's
//   acceleration better than the causal estimate did.

#include <array>
#include <cstddef>

#include "estimator/friction_model.hpp"
#include "estimator/motion.hpp"

namespace tsmh::estimator {

class Differentiator;

/// The hindsight correction's settings. Deployed as they are; the accuracy
/// harnesses vary them (online_accuracy --hindsight-*, model_accuracy
/// --variants).
struct HindsightConfig {
  /// s after each sample, the fine channel's state extrapolated back gives
  /// that sample's acceleration (0: off). The history holds kHistory - 2
  /// samples of lag (62 ms at 1 kHz); at higher rates, or with a longer lag,
  /// a sample is looked at when it is about to leave the history.
  double lag = 0.05;
  /// |xdd| (rad/s^2) where the sign from hindsight starts to count and where
  /// it decides alone (weight clamp((|xdd| - sure) / (certain - sure), 0, 1),
  /// the rest the causal sign); within the differentiator's cruise_armed_time
  /// of a manoeuvre, the `_armed` pair, since the true xdd may be exactly 0.
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

/// Steps the model again where hindsight settles sgn(xdd) differently from
/// the sign the model was given: below |xd| = lambda a sign decided late or
/// wrongly moves the friction state the wrong way, and the error would last
/// until the next saturation (0.3 s and more); this ends it after `lag`.
/// Keeps the last samples as the model was stepped with them (motion,
/// friction, the model's state). Never allocates.
class HindsightCorrection {
 public:
  HindsightCorrection() = default;
  /// `enabled`: the caller's model saves its state and reads the sign, and
  /// the differentiator runs the fine channel.
  HindsightCorrection(const HindsightConfig& config, bool enabled);

  bool enabled() const noexcept { return enabled_; }
  /// Empties the history (reset, a restart after a gap).
  void forget() noexcept { size_ = pending_ = 0; }
  /// Records the sample the model was just stepped with (`friction` its
  /// result; the model holds the state after it), then looks at the samples
  /// `lag` old again with what `diff` has seen since. Returns the newest
  /// sample's friction, corrected when a correction reached it.
  double update(const Motion& m, double friction, const Differentiator& diff,
                FrictionDynamics& model) noexcept;
  /// Samples stepped again (the corrected sample and every later one).
  std::size_t resteps() const noexcept { return resteps_; }

 private:
  struct Sample {
    Motion m;
    double friction = 0.0;
    DynamicsState state;
  };
  // 64 samples (22 kB with the model's state): the deployed lag at 1 kHz
  // and the look-ahead, within a core's first-level cache.
  static constexpr std::size_t kHistory = 64;
  bool step_again(std::size_t j, const Motion& m, bool dirty, FrictionDynamics& model) noexcept;
  void catch_up(std::size_t from, FrictionDynamics& model) noexcept;
  std::size_t index_back(std::size_t back) const noexcept {
    return (newest_ + kHistory - back) % kHistory;
  }

  HindsightConfig cfg_;
  bool enabled_ = false;
  double inv_span_ = 0.0, inv_span_armed_ = 0.0;  // 1 / (certain - sure)
  std::array<Sample, kHistory> history_{};
  // newest_: the newest sample; the oldest `pending_` of the newest are not
  // yet past lag. The sample before the oldest pending one is kept too: its
  // state is where a correction steps again from.
  std::size_t newest_ = 0, size_ = 0, pending_ = 0;
  std::size_t resteps_ = 0;
};

}  // namespace tsmh::estimator
