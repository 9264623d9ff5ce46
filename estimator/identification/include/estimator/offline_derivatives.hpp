#pragma once
// Offline, zero-phase velocity and acceleration of a recorded angle, for
// identification (`tsm fit`) and the model-gap workflow (`tsm gap`).
//
// The online Differentiator (differentiator.hpp) must be causal, so it lags
// and debounces the sign of the acceleration; parameters fitted on its output
// absorb those errors. A recording is available whole, so here the same
// white-jerk Kalman filter runs forwards and a Rauch-Tung-Striebel smoother
// backwards: every estimate uses past and future samples alike (no lag), and
// the smoothed acceleration is accurate enough that its plain sign is the
// model's sgn(xdd). The parameters found are then the physical ones, which
// the online estimator uses as they are. Measurements: docs/identification.md.

#include <span>
#include <vector>

#include "estimator/motion.hpp"
#include "estimator/recording.hpp"
#include "estimator/reference_encoder.hpp"

namespace tsmh::estimator {

struct OfflineDerivativeConfig {
  /// Spectral density of the jerk the smoother expects, (rad/s^3)^2/Hz.
  /// Larger follows faster motion with more noise (docs/identification.md
  /// has the sweep that chose it).
  double jerk_psd = 10.0;
  /// Encoder quantum, rad (uniform error quantum^2/12 is the measurement noise).
  double quantum = kReferenceQuantum;
  /// Additional white measurement noise on the angle, rad (standard deviation).
  double position_noise = 0.0;
  /// sgn(xdd) is 0 while |xdd| is below this many standard deviations of the
  /// smoothed acceleration (0: the plain sign).
  double acc_sign_sigmas = 0.5;
  /// Pass the expected sign E[sgn(xdd)] = erf(xdd / (sqrt 2 sd)) in
  /// [-1, 1] (eqs. 4-10 are linear in sgn(xdd); Motion::acc_sign) rather
  /// than a hard sign beyond acc_sign_sigmas (measured: docs/identification.md).
  bool expected_sign = true;
};

struct SmoothedDerivatives {
  std::vector<double> x, xd, xdd;  ///< rad, rad/s, rad/s^2 at every sample
  std::vector<double> xdd_std;     ///< posterior standard deviation of xdd, rad/s^2
};

/// Fixed-interval RTS smoothing of x(t). t strictly increasing (uneven
/// intervals are handled exactly). Throws std::invalid_argument on size
/// mismatch or fewer than 3 samples.
SmoothedDerivatives smooth_derivatives(std::span<const double> t, std::span<const double> x,
                                       const OfflineDerivativeConfig& config = {});

/// Motion samples for every row of `rec` from the smoothed angle derivatives
/// (x is the recorded angle; load = |tau_in|/R when both are known).
std::vector<Motion> offline_motion(const Recording& rec,
                                   const OfflineDerivativeConfig& config = {});

}  // namespace tsmh::estimator
