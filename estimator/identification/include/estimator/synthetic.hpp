#pragma once
// Synthetic recordings for identification and model-gap tests and benchmarks:
// a known "true" friction model driven by multi-sine motion, observed through
// realistic sensors (noisy torque channels, a quantised encoder). Knowing the
// true friction lets a test score a fit against the truth, not the noise.
//
// The world: the input pulley follows one of several motion kinds (a sum of
// sines by default; random phases from the seed, faded in from rest during a
// 1 s pre-roll before the recording starts, so a recording begins in ordinary
// motion; see MotionKind); the distal side carries a
// slow random load torque tau_out; the proximal torque is
// tau_in = tau_out + R F_true. Friction is simulated with the exact
// derivatives, `substeps` times per sample, and the transmitted load the
// model sees is |tau_in| / R from the previous substep (the load depends on
// the friction it causes).

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include "estimator/friction_model.hpp"
#include "estimator/recording.hpp"
#include "estimator/reference_encoder.hpp"

namespace tsmh::estimator {

/// How the input pulley moves. Every kind has exact, continuous velocity and
/// acceleration, so the true model runs on exact derivatives.
enum class MotionKind {
  kMultisine,  ///< sum of `components` sines, log-spaced in [f_low_hz, f_high_hz]
  kSurgeon,    ///< smooth point-to-point moves (bell-shaped velocity) between holds at rest
  kReversals,  ///< constant-speed strokes joined by fast reversals (40-120 ms)
  kCreep,      ///< slow motion: speeds of 5-50 mrad/s changing smoothly, with pauses
};

struct SyntheticConfig {
  double duration_s = 40.0;
  double rate_hz = 1000.0;
  double radius_m = 0.01;
  /// Standard deviation of the white noise on each torque channel, N m.
  double torque_noise = 0.003;
  /// Encoder quantum of x_in, rad (0: unquantised).
  double quantum = kReferenceQuantum;
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
  MotionKind motion = MotionKind::kMultisine;
  /// Sampling-time jitter: each sample is taken at i/rate + U(-jitter, +jitter) s
  /// (kept below half a period, so times stay increasing).
  double jitter_s = 0.0;
  /// Fraction of samples lost (removed from the recording), in [0, 0.5].
  double drop_fraction = 0.0;
  /// Record the 1 s pre-roll too (times from -1 s), so the recording starts
  /// at rest with the friction state at zero, as an online estimator does.
  bool from_rest = false;
  /// A tremor added to the motion: tremor_rad sin(2 pi tremor_hz t), exact
  /// derivatives included (0: none). At 1e-12 rad it changes no encoder
  /// sample, yet it gives the acceleration a sign wherever the motion's own
  /// acceleration is smaller than tremor_rad (2 pi tremor_hz)^2: in holds and
  /// cruises, where eq. (4)'s lambda sgn(xdd) then drives the true state.
  double tremor_rad = 0.0;
  double tremor_hz = 10.0;
  /// A constant acceleration added to the motion, rad/s^2 (x += a t^2 / 2
  /// from t = 0 of the pre-roll on). At +-1e-16 it moves no encoder sample in
  /// 40 s, yet holds and cruises then accelerate (or decelerate) throughout.
  double drift_acc = 0.0;
  std::uint64_t seed = 1;
};

struct SyntheticData {
  Recording recording;                ///< what the sensors saw
  std::vector<double> true_friction;  ///< N, the true F at every sample (noise-free)
};

/// Runs `truth` (cloned, not modified) on the configured world. Throws
/// std::invalid_argument for an unusable config.
SyntheticData make_synthetic(const FrictionModel& truth, const SyntheticConfig& config = {});

/// "multisine", "surgeon", "reversals", "creep"; nullopt for anything else.
std::optional<MotionKind> motion_kind_from_name(std::string_view name);
const char* motion_kind_name(MotionKind kind);

}  // namespace tsmh::estimator
