#pragma once
// The interfaces every friction model implements: the paper's composable
// tendon-sheath model and the baselines (Dahl, LuGre, Kaneko's Coulomb/capstan).
// Two faces, for two kinds of user:
// - FrictionDynamics, what the 1 kHz loop calls: step() once per sample,
//   never allocates and never throws;
// - FrictionModel, what identification and the params files add: the
//   model's family, its parameters and how to set them, copies.

#include <array>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "estimator/motion.hpp"

namespace tsmh::estimator {

/// One identifiable parameter: qualified name ("stribeck.mu1", "core.theta"),
/// value and the bounds a fit may search in.
struct Parameter {
  std::string name;
  double value = 0.0;
  double lower = 0.0;
  double upper = 0.0;
  bool fixed = false;  ///< excluded from identification (e.g. the paper's integer n)
  std::string unit;
};

/// A model's internal state as a value: what step() changes, so that a
/// stretch of samples can be stepped again from an earlier state (the
/// estimator's hindsight correction). Its meaning is the model's own.
struct DynamicsState {
  /// The paper's state (6), the distributed-slip elements, their Coulomb
  /// play and their last angle, the friction of the last step, and the
  /// distal family's elements and last angle.
  std::array<double, 49> v{};
};

/// The real-time face of a model: a stateful value object stepped once per
/// sample.
class FrictionDynamics {
 public:
  virtual ~FrictionDynamics() = default;

  /// Clears the internal state (friction zero, at rest).
  virtual void reset() noexcept = 0;

  /// Advances the internal state over `dt` seconds ending at sample `m` and
  /// returns the total friction F in N. Non-finite input or dt <= 0 leaves the
  /// state unchanged and returns the previous F.
  virtual double step(const Motion& m, double dt) noexcept = 0;

  /// The friction returned by the last step().
  virtual double friction() const noexcept = 0;

  /// What one step gives the estimator: the friction and the sliding level
  /// at the step's motion.
  struct StepResult {
    double friction = 0.0;          ///< N, step()'s result
    double sliding_friction = 0.0;  ///< N, sliding_friction() after the step
  };
  /// step(), then sliding_friction(): the same two results in one call (the
  /// estimator's per-sample call; both come back in registers). Models
  /// override it to save the second virtual call. Never allocates or throws.
  virtual StepResult step_with_level(const Motion& m, double dt) noexcept {
    const double f = step(m, dt);
    return {f, sliding_friction()};
  }

  /// Sets the internal state so that the friction is as close to `friction`
  /// (N) as the model allows at rest at `m` (e.g. within +-gamma Ff). Models
  /// without a settable state ignore it. Never allocates or throws.
  virtual void preset(double /*friction*/, const Motion& /*m*/) noexcept {}

  /// The sliding friction level at the last step's motion, N (> 0): what
  /// |F| tends to while the input slides one way. Past a reversal |F| climbs
  /// to it over the friction's transition; a sample still far below it has
  /// not left the transition. NaN for models without such a level.
  virtual double sliding_friction() const noexcept {
    return std::numeric_limits<double>::quiet_NaN();
  }
  /// Multiplies the model's sliding level by k_positive where the input
  /// slides positive (xd >= 0) and by k_negative where it slides negative,
  /// from the next step on, leaving the state, and so the friction of this
  /// instant, as it is: how a re-routed sheath's friction changes (the levels
  /// grow with the wrap, each direction's with its own sheath; the stiffness
  /// of a reversal's transition does not). Returns false, and changes
  /// nothing, for models without such a level or a scale that is not a
  /// finite number > 0 (the caller then scales the output instead). Never
  /// allocates or throws.
  virtual bool set_level_scales(double /*k_positive*/, double /*k_negative*/) noexcept {
    return false;
  }
  /// The same scale both ways.
  bool set_level_scale(double k) noexcept { return set_level_scales(k, k); }
  /// Whether step() reads Motion::acc_sign (the sign of the acceleration):
  /// when it does not, the estimator's corrections of that sign have nothing
  /// to correct and are skipped.
  virtual bool reads_acceleration_sign() const noexcept { return true; }
  /// Copies the internal state into `out`; false (nothing written) for
  /// models that do not support it. Never allocates or throws.
  virtual bool save_state(DynamicsState& /*out*/) const noexcept { return false; }
  /// Sets the internal state to one save_state() wrote for this model.
  virtual void restore_state(const DynamicsState& /*state*/) noexcept {}
};

/// The identification face: what a fit searches and a params file holds.
class FrictionModel : public FrictionDynamics {
 public:
  /// Stable id of the model family: "tsm", "dahl", "lugre", "coulomb_capstan".
  virtual std::string kind() const = 0;

  /// Parameters in a fixed order; set_values() takes values in the same order.
  virtual std::vector<Parameter> parameters() const = 0;
  /// Replaces the parameter values (size must equal parameters().size(); values
  /// are used as given, callers clamp to bounds). Resets the internal state.
  virtual void set_values(std::span<const double> values) = 0;

  virtual std::unique_ptr<FrictionModel> clone() const = 0;
};

}  // namespace tsmh::estimator
