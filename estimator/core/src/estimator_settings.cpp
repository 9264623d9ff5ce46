#include "estimator/estimator_settings.hpp"

#include <cmath>
#include <sstream>

namespace tsmh::estimator {

DifferentiatorConfig EstimatorSettings::differentiator() const {
  DifferentiatorConfig d;
  d.sign_mode = sign;
  d.cruise_window = cruise_window;
  d.fine_psd = fine_psd;
  d.hindsight_lag = hindsight_lag;
  d.quantum = encoder_quantum_rad;
  return d;
}

std::string NumericSetting::problem(double v) const {
  if (std::isfinite(v) && v >= lo && v <= hi && !(lo_open && v == lo)) return "";
  std::ostringstream range;
  range << "must be within " << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
  return range.str();
}

const std::array<NumericSetting, 4>& numeric_settings() {
  using L = DifferentiatorLimits;
  static const std::array<NumericSetting, 4> settings{{
      {"cruise_window", "--cruise-window",
       "smooth sign: window of the cruise hypothesis, s (0: off)", 0.0, L::kCruiseWindow, false,
       &EstimatorSettings::cruise_window},
      {"fine_psd", "--fine-psd",
       "smooth sign: crackle spectral density of the fine acceleration channel, "
       "(rad/s^5)^2/Hz (0: off)",
       0.0, L::kFinePsd, false, &EstimatorSettings::fine_psd},
      {"hindsight_lag", "--hindsight-lag",
       "smooth sign with the fine channel: lag of the hindsight correction, s (0: off)", 0.0,
       L::kHindsightLag, false, &EstimatorSettings::hindsight_lag},
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
