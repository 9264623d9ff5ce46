#pragma once
// Synthetic recordings for identification and model-gap tests and benchmarks:
// a known "true" friction model driven by multi-sine motion, observed through
// realistic sensors (noisy torque channels, a quantised encoder). Knowing the
// true friction lets a test score a fit against the truth, not the noise.
//
// The world: the input pulley follows a sum of sines (random phases from the
// seed, faded in from rest during a 1 s pre-roll before the recording starts,
// so a recording begins in ordinary motion); the distal side carries a
// slow random load torque tau_out; the proximal torque is
// tau_in = tau_out + R F_true. Friction is simulated with the exact
// derivatives, `substeps` times per sample, and the transmitted load the
// model sees is |tau_in| / R from the previous substep (the load depends on
// the friction it causes).

#include <cstdint>
#include <numbers>
#include <vector>

#include "estimator/friction_model.hpp"
#include "estimator/recording.hpp"

namespace tsmh::estimator {

struct SyntheticConfig {
  double duration_s = 40.0;
  double rate_hz = 1000.0;
  double radius_m = 0.01;
  /// Standard deviation of the white noise on each torque channel, N m.
  double torque_noise = 0.003;
  /// Encoder quantum of x_in, rad (0: unquantised).
  double quantum = 2.0 * std::numbers::pi / 40960.0;
  /// Largest |x_in| of the multi-sine, rad.
  double amplitude_rad = 1.0;
  /// Lowest and highest frequency of the multi-sine, Hz (log-spaced components).
  double f_low_hz = 0.07;
  double f_high_hz = 1.2;
  int components = 7;
  /// Peak of the slow distal load torque, N m (0: no load).
  double load_amplitude = 0.06;
  /// Offset of the distal load torque, N m (a preloaded joint).
  double load_offset = 0.0;
  /// Integration substeps of the true model per sample.
  int substeps = 4;
  /// Also store the exact xd_in, xdd_in columns (a simulator's recording).
  bool exact_derivatives = false;
  std::uint64_t seed = 1;
};

struct SyntheticData {
  Recording recording;                ///< what the sensors saw
  std::vector<double> true_friction;  ///< N, the true F at every sample (noise-free)
};

/// Runs `truth` (cloned, not modified) on the configured world. Throws
/// std::invalid_argument for an unusable config.
SyntheticData make_synthetic(const FrictionModel& truth, const SyntheticConfig& config = {});

}  // namespace tsmh::estimator
