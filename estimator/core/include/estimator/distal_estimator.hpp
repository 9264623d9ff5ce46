#pragma once
// The per-joint distal torque estimator the haptic loop calls every tick:
// proximal tension and motor angle in, estimated distal (tip) torque out.
//   tau_in = R (T1 - T3)            (eq. 1)
//   F      = friction model         (eqs. 4-12), driven by the differentiated angle
//   tau_out_est = tau_in - R F      (eq. 3)

#include <array>
#include <cstddef>
#include <limits>
#include <memory>

#include "estimator/differentiator.hpp"
#include "estimator/friction_model.hpp"

namespace tsmh::estimator {

struct Estimate {
  double xd = 0.0;           ///< rad/s (from the differentiator or given)
  double xdd = 0.0;          ///< rad/s^2
  double acc_sign = 0.0;     ///< sgn(xdd) as the model used it
  double tau_in = 0.0;       ///< N m, proximal torque
  double friction = 0.0;     ///< N, total sheath friction F
  double tau_out_est = 0.0;  ///< N m, estimated distal torque; NaN when !valid
  bool valid = false;        ///< false: the sample was rejected (non-finite, time not increasing)
  /// N, the model's sliding friction level at this sample (|friction| tends
  /// to it while sliding one way; FrictionDynamics::sliding_friction). NaN
  /// when the model has none.
  double friction_level = std::numeric_limits<double>::quiet_NaN();
  /// N, the mean proximal tension the model was given (NaN: none).
  double tension = std::numeric_limits<double>::quiet_NaN();
};

/// The friction state the estimator starts from (and restarts from after
/// reset()), before any motion has shown it.
enum class StartState {
  /// The tip is free at the first sample: the proximal torque is all
  /// friction, F = tau_in / R, within what the model allows at rest. Like
  /// taring a force sensor; a session starts with the instrument free.
  kFreeTip,
  /// Zero friction state (the paper's initial condition): whatever friction
  /// the sheath holds at start reads as tip torque until motion saturates it.
  kZero,
};

class DistalTorqueEstimator {
 public:
  /// `model` is owned (only its real-time face is used); radius_m > 0
  /// (throws std::invalid_argument otherwise).
  DistalTorqueEstimator(std::unique_ptr<FrictionDynamics> model, double radius_m,
                        const DifferentiatorConfig& diff = {},
                        StartState start = StartState::kFreeTip);

  /// One sample with the proximal torque given; `tension` (N) is the mean of
  /// the two proximal tensions when known (models with tension copies use
  /// it, distributed_slip.hpp), NaN otherwise. Never allocates or throws.
  Estimate update(double t, double x_in, double tau_in,
                  double tension = std::numeric_limits<double>::quiet_NaN()) noexcept;
  /// One sample from the two proximal tensions (eq. 1): tau_in = R (T1 - T3),
  /// and their mean for the model's tension copies.
  Estimate update_tensions(double t, double x_in, double t1, double t3) noexcept {
    return update(t, x_in, radius_ * (t1 - t3), 0.5 * (t1 + t3));
  }
  /// One sample with exact derivatives (a simulator that knows them).
  Estimate update_exact(double t, double x_in, double xd, double xdd, double tau_in,
                        double tension = std::numeric_limits<double>::quiet_NaN()) noexcept;

  void reset() noexcept;
  double radius() const { return radius_; }
  /// Whether the hindsight correction runs (DifferentiatorConfig::
  /// hindsight_lag > 0, the smooth sign with the fine channel, and a model
  /// whose state can be saved and that reads the sign of the acceleration).
  bool hindsight() const { return hindsight_; }
  /// Samples the hindsight correction stepped the model again for (the
  /// corrected sample and every later one), since construction.
  std::size_t hindsight_resteps() const { return resteps_; }
  const FrictionDynamics& model() const { return *model_; }
  /// The model's level scales (FrictionDynamics::set_level_scales): false when
  /// the model has none. Never allocates or throws.
  bool set_level_scales(double k_positive, double k_negative) noexcept {
    return model_->set_level_scales(k_positive, k_negative);
  }

 private:
  Estimate finish(double t, double x, double xd, double xdd, double acc_sign, double tau_in,
                  double tension) noexcept;
  void look_back(double t) noexcept;
  // Steps sample j again with the motion m from the state before it (on the
  // corrected path when `dirty`): true when that changed its friction, so
  // that the samples after it must be stepped again. Kept unless the change
  // is too small to matter and the path is not dirty.
  bool step_again(std::size_t j, const Motion& m, bool dirty) noexcept;
  // Steps every sample after `from` to the newest again, from the state the
  // model holds (from's): the model then holds the corrected newest state.
  void catch_up(std::size_t from) noexcept;
  // Steps the sample `back` samples old and every younger one again.
  void step_again_from(std::size_t back) noexcept;
  // Empties the history and what is read from it (reset, a restart).
  void forget_history() noexcept;
  void settle_reversal() noexcept;
  // Records a change of the encoder reading at t, to x_in (before the
  // sample joins the history): true when a move from rest has shown enough
  // counts to tell when it started (settle_start() is then due).
  bool record_crossing(double t, double x_in) noexcept;
  void settle_start() noexcept;
  void settle_turn() noexcept;
  // When the last changes went the same way and slowed down (a move
  // running out), the time it stops (settle_stops), else NaN.
  double estimated_stop() const noexcept;
  // The encoder reading's changes in the current run (in a row the same
  // way), each taken halfway between the samples before and at it; the
  // newest kCrossings of them.
  static constexpr std::size_t kCrossings = 16;
  struct Crossings {
    std::array<double, kCrossings> t{};
    std::size_t newest = 0;
    std::size_t run = 0;      // changes in the run (0: none since the (re)start)
    double direction = 0.0;   // the run's: +1 or -1
    bool start_open = false;  // a run from rest whose start is still to settle
    bool turn_open = false;   // a run from a turn, still to settle
    double turn_from = 0.0;   // ... the old way's last change
    double at(std::size_t back) const { return t[(newest + kCrossings - back) % kCrossings]; }
    // The newest n (<= kCrossings) times, oldest first.
    std::array<double, kCrossings> oldest_first(std::size_t n) const {
      std::array<double, kCrossings> out{};
      for (std::size_t k = 0; k < n; ++k)
        out[k] = at(n - 1 - k);
      return out;
    }
  };
  Crossings crossings_;
  // estimated_stop() for the current still stretch, once looked up.
  double stop_ = 0.0;
  bool stop_known_ = false;
  // The last four distinct encoder readings, newest first, and how many
  // samples since repeated the newest (settle_reversal).
  std::array<double, 4> counts_{};
  std::size_t counts_seen_ = 0, repeats_ = 0;

  // The hindsight correction's history: the last samples as the model was
  // stepped with them, newest at newest_; the oldest `pending_` of the newest
  // are not yet past hindsight_lag. The sample before the oldest pending one
  // is kept too: its state is where a correction steps again from.
  struct Sample {
    Motion m;  // its interval: m.t less the previous sample's
    double friction = 0.0;
    bool settled = false;  // its sign set by settle_reversal() or settle_start()
    DynamicsState state;
  };
  // 256 ms at 1 kHz: a slow start is settled up to about 150 ms after the
  // move began (settle_start(), once its counts span settle_span).
  static constexpr std::size_t kHistory = 256;
  // settle_reversal() looks at still stretches of at most this many
  // samples; a longer one is a hold (settle_start()).
  static constexpr std::size_t kReversalSpan = 128;
  std::array<Sample, kHistory> history_{};
  std::size_t newest_ = 0, size_ = 0, pending_ = 0;
  // The history's index of the sample `back` samples older than the newest.
  std::size_t index_back(std::size_t back) const noexcept {
    return (newest_ + kHistory - back) % kHistory;
  }
  Sample& sample_back(std::size_t back) noexcept { return history_[index_back(back)]; }
  bool hindsight_ = false;
  double inv_span_ = 0.0, inv_span_armed_ = 0.0;  // 1 / (certain - sure)
  std::size_t resteps_ = 0;

  std::unique_ptr<FrictionDynamics> model_;
  double radius_;
  Differentiator diff_;
  StartState start_;
  bool started_ = false;
  double t_prev_ = 0.0;
};

}  // namespace tsmh::estimator
