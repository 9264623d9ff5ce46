#include "estimator/estimator_settings.hpp"

#include <cmath>
#include <sstream>

namespace tsmh::estimator {

DifferentiatorConfig EstimatorSettings::differentiator() const {
  DifferentiatorConfig d;
  d.quantum = encoder_quantum_rad;
  return d;
}

std::string NumericSetting::problem(double v) const {
  if (std::isfinite(v) && v >= lo && v <= hi && !(lo_open && v == lo)) return "";
  std::ostringstream range;
  range << "must be within " << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
  return range.str();
}

const std::array<NumericSetting, 1>& numeric_settings() {
  using L = DifferentiatorLimits;
  static const std::array<NumericSetting, 1> settings{{
      {"encoder_quantum_rad", "--encoder-quantum",
       "resolution of x_in, rad: the differentiator's measurement noise and rest time "
       "(default 2 pi / 40960)",
       0.0, L::kEncoderQuantum, true, &EstimatorSettings::encoder_quantum_rad},
  }};
  return settings;
}

std::optional<StartState> start_state_from_name(std::string_view name) {
  if (name == "free_tip") return StartState::kFreeTip;
  if (name == "zero") return StartState::kZero;
  return std::nullopt;
}

}  // namespace tsmh::estimator
