#pragma once
// The settings of one joint's online estimator that a user chooses: what the
// installation is (the encoder's resolution) and how a session starts. The
// rest of the estimator (the differentiator's channels, its sign and the
// corrections) is deployed as it is; the accuracy harnesses vary it. One
// table names each numeric setting (its YAML key in haptic-server's
// `joints:`, its flag on `tsm simulate`), its range and its meaning, so that
// both programs read the same settings under the same limits and say the
// same thing about a bad value.

#include <array>
#include <optional>
#include <string>
#include <string_view>

#include "estimator/differentiator.hpp"
#include "estimator/distal_estimator.hpp"

namespace tsmh::estimator {

struct EstimatorSettings {
  /// Resolution of the motor angle x_in as the slave reports it, rad (the
  /// encoder's count through any gearing): the differentiator's measurement
  /// noise, quantum^2/12, and its rest time.
  double encoder_quantum_rad = DifferentiatorConfig{}.quantum;
  /// The estimator's friction state at the first sample.
  StartState start_state = StartState::kFreeTip;

  /// The differentiator these settings configure (the rest as deployed).
  DifferentiatorConfig differentiator() const;
};

/// One numeric setting: where a user writes it and what it accepts.
struct NumericSetting {
  std::string_view key;   ///< YAML key in a haptic-server `joints:` entry
  std::string_view flag;  ///< `tsm simulate` flag
  std::string_view help;  ///< what it is, its unit, what 0 means
  double lo = 0.0;
  double hi = 0.0;
  bool lo_open = false;  ///< lo itself is refused
  double EstimatorSettings::*field = nullptr;

  /// "" when `v` is a valid value, else why not ("must be within (0, 0.1]").
  std::string problem(double v) const;
};

/// The numeric settings, in the order the programs list them.
const std::array<NumericSetting, 1>& numeric_settings();

/// The words a user writes for the start state.
inline constexpr std::string_view kStartStateNames = "free_tip or zero";
std::optional<StartState> start_state_from_name(std::string_view name);

}  // namespace tsmh::estimator
