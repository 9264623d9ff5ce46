#pragma once
// Running a friction model over a whole recording, as `tsm simulate`, the
// identification and the gap workflow do. The motion (velocity, acceleration,
// debounced acceleration sign) does not depend on the model's parameters, so
// it is computed once and reused for every model evaluation.

#include <span>
#include <vector>

#include "estimator/differentiator.hpp"
#include "estimator/friction_model.hpp"
#include "estimator/motion.hpp"
#include "estimator/recording.hpp"

namespace tsmh::estimator {

enum class DerivativeSource {
  kAutomatic,       ///< xd_in/xdd_in when the recording has them, else the differentiator
  kDifferentiator,  ///< always the project's differentiator, as deployed in the loop
  kExact,           ///< xd_in/xdd_in (throws DataError when absent)
};

/// Motion samples for every row of `rec`. load = |tau_in|/R and drive =
/// tau_in/R when both are known; tension = (T1 + T3)/2 when both are present.
std::vector<Motion> motion_from_recording(const Recording& rec, DerivativeSource source,
                                          const DifferentiatorConfig& diff = {});

/// F (N) at every sample: the model is reset, then stepped from the first
/// sample (F[0] = 0, the state at rest) with the recording's own intervals.
std::vector<double> simulate_friction(FrictionModel& model, std::span<const Motion> motion);

/// The same into a caller's buffer (no allocation; out.size() == motion.size()).
void simulate_friction_into(FrictionModel& model, std::span<const Motion> motion,
                            std::span<double> out) noexcept;

}  // namespace tsmh::estimator
