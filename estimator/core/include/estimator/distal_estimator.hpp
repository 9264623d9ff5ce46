#pragma once
// The per-joint distal torque estimator the haptic loop calls every tick:
// proximal tension and motor angle in, estimated distal (tip) torque out.
//   tau_in = R (T1 - T3)            (eq. 1)
//   F      = friction model         (eqs. 4-12), driven by the differentiated angle
//   tau_out_est = tau_in - R F      (eq. 3)

#include <cstddef>
#include <limits>
#include <memory>

#include "estimator/corrections.hpp"
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
  /// (throws std::invalid_argument otherwise). `corrections`: the
  /// corrections' settings (corrections.hpp), deployed as they are.
  DistalTorqueEstimator(std::unique_ptr<FrictionDynamics> model, double radius_m,
                        const DifferentiatorConfig& diff = {},
                        StartState start = StartState::kFreeTip,
                        const CorrectionsConfig& corrections = {});

  /// One sample with the proximal torque given; `tension` (N) is the mean of
  /// the two proximal tensions when known (models with tension copies use
  /// it, distributed_slip.hpp), NaN otherwise; `x_out` (rad) the distal
  /// joint angle where an encoder measures it, NaN otherwise (a non-finite
  /// value reads as NaN: the model takes the tendon as rigid). Never
  /// allocates or throws.
  Estimate update(double t, double x_in, double tau_in,
                  double tension = std::numeric_limits<double>::quiet_NaN(),
                  double x_out = std::numeric_limits<double>::quiet_NaN()) noexcept;
  /// One sample from the two proximal tensions (eq. 1): tau_in = R (T1 - T3),
  /// and their mean for the model's tension copies.
  Estimate update_tensions(double t, double x_in, double t1, double t3,
                           double x_out = std::numeric_limits<double>::quiet_NaN()) noexcept {
    return update(t, x_in, radius_ * (t1 - t3), 0.5 * (t1 + t3), x_out);
  }
  /// One sample with exact derivatives (a simulator that knows them).
  Estimate update_exact(double t, double x_in, double xd, double xdd, double tau_in,
                        double tension = std::numeric_limits<double>::quiet_NaN(),
                        double x_out = std::numeric_limits<double>::quiet_NaN()) noexcept;

  void reset() noexcept;
  double radius() const { return radius_; }
  /// Whether the hindsight correction runs (HindsightConfig::lag > 0, the
  /// smooth sign with the fine channel, and a model whose state can be saved
  /// and that reads the sign of the acceleration).
  bool hindsight() const { return hindsight_.enabled(); }
  /// Whether the rest and cruise corrections run: not for a model that reads
  /// no sign of the acceleration (they act on that sign alone).
  bool sign_corrections() const {
    return diff_.rest().still_time() > 0.0 || diff_.cruise().enabled();
  }
  /// Samples the hindsight correction stepped the model again for (the
  /// corrected sample and every later one), since construction.
  std::size_t hindsight_resteps() const { return hindsight_.resteps(); }
  const FrictionDynamics& model() const { return *model_; }
  /// The model's level scales (FrictionDynamics::set_level_scales): false when
  /// the model has none. Never allocates or throws.
  bool set_level_scales(double k_positive, double k_negative) noexcept {
    return model_->set_level_scales(k_positive, k_negative);
  }

 private:
  Estimate finish(const Motion& m, double xdd, double tau_in) noexcept;

  std::unique_ptr<FrictionDynamics> model_;
  double radius_;
  CorrectedDifferentiator diff_;
  StartState start_;
  HindsightCorrection hindsight_;
  bool started_ = false;
  double t_prev_ = 0.0;
};

}  // namespace tsmh::estimator
