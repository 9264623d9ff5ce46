#pragma once
// The encoder every default in the estimator is set for: the slave's motor
// encoder, 40960 counts per turn. The differentiator's settings were chosen
// at this resolution; the synthetic recordings and the offline derivatives
// default to it so that all three describe the same sensor.

#include <numbers>

namespace tsmh::estimator {

/// The reference encoder's quantum, rad (2 pi / 40960).
inline constexpr double kReferenceQuantum = 2.0 * std::numbers::pi / 40960.0;

}  // namespace tsmh::estimator
