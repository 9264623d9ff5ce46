#pragma once
// Configured plausibility ranges for incoming messages. A value outside its
// range (or NaN/Inf) rejects the whole message: the loop must never act on a
// sample that a sensor glitch or a hostile sender produced. The defaults are
// generous bounds for a NOTES-scale robot; a deployment tightens them in its
// configuration.

#include <limits>

namespace tsmh::bridge {

/// Closed interval [lo, hi]. The default accepts every finite value.
struct Range {
  double lo = -std::numeric_limits<double>::max();
  double hi = std::numeric_limits<double>::max();
  constexpr bool contains(double v) const noexcept { return v >= lo && v <= hi; }
};

struct SlaveStateLimits {
  Range x_in{-1000.0, 1000.0};    ///< rad; the motor pulley turns many times
  Range x_out{-10.0, 10.0};       ///< rad; NaN allowed (joint without encoder)
  Range tension{-200.0, 5000.0};  ///< N, both T1 and T3; load cells read slightly negative at rest
  Range radius_m{1e-4, 0.5};      ///< m

  // Plausible steps: a value may change from the last accepted
  // sample by at most rate * (elapsed + step_slack_s), elapsed being the
  // smaller of the utime and the receive-time intervals (a forged utime
  // cannot widen the bound). 0 disables a check. Beyond them a message is
  // rejected as Implausible; after InboxOptions::resync_after of them in a
  // row the channel re-bases on the newest (a real re-homing is not blocked
  // forever).
  double max_x_in_rate_rad_s = 500.0;           ///< motor pulley: ~4800 rpm
  double max_x_out_rate_rad_s = 100.0;          ///< joint encoder
  double max_tension_rate_n_per_s = 100'000.0;  ///< load cell: 100 N per millisecond
  double step_slack_s = 0.002;                  ///< two 1 kHz periods of jitter and batching
};

struct SlaveTruthLimits {
  Range tau_out, friction, tau_in, x_out, contact_force, indentation;  ///< finite only by default
};

struct MasterCommandLimits {
  Range position_ref{-10.0, 10.0};  ///< rad
};

/// HAPTIC_STATUS is informational and may carry NaN (e.g. no estimate yet):
/// only its structure (decode, joint count) and ordering are checked.
struct HapticStatusLimits {};

/// CALIBRATION_REQUEST carries only flags: structure and ordering are checked.
struct CalibrationRequestLimits {};

}  // namespace tsmh::bridge
