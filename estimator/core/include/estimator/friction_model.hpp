#pragma once
// The interface every friction model implements: the paper's composable
// tendon-sheath model and the baselines (Dahl, LuGre, Kaneko's Coulomb/capstan).
// Models are stateful value objects: step() is called once per sample, never
// allocates and never throws, so the 1 kHz loop can call it.

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

class FrictionModel {
 public:
  virtual ~FrictionModel() = default;

  /// Stable id of the model family: "tsm", "dahl", "lugre", "coulomb_capstan".
  virtual std::string kind() const = 0;

  /// Parameters in a fixed order; set_values() takes values in the same order.
  virtual std::vector<Parameter> parameters() const = 0;
  /// Replaces the parameter values (size must equal parameters().size(); values
  /// are used as given, callers clamp to bounds). Resets the internal state.
  virtual void set_values(std::span<const double> values) = 0;

  /// Clears the internal state (friction zero, at rest).
  virtual void reset() noexcept = 0;

  /// Advances the internal state over `dt` seconds ending at sample `m` and
  /// returns the total friction F in N. Non-finite input or dt <= 0 leaves the
  /// state unchanged and returns the previous F.
  virtual double step(const Motion& m, double dt) noexcept = 0;

  /// The friction returned by the last step().
  virtual double friction() const noexcept = 0;

  /// Sets the internal state so that the friction is as close to `friction`
  /// (N) as the model allows at rest at `m` (e.g. within +-gamma Ff). Models
  /// without a settable state ignore it. Never allocates or throws.
  virtual void preset(double /*friction*/, const Motion& /*m*/) noexcept {}

  virtual std::unique_ptr<FrictionModel> clone() const = 0;
};

}  // namespace tsmh::estimator
