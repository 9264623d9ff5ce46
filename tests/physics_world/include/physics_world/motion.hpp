#pragma once
// How the input pulley moves: motion kinds written for this world (not the
// estimator's synthetic generator), each with exact, continuous velocity
// and acceleration, starting at rest at x = 0.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "physics_world/world.hpp"

namespace tsmh::physics_world {

enum class MotionKind {
  kMultisine,  ///< seven sines log-spaced in 0.1-1 Hz, random phases, faded in; peak 1 rad
  kSurgeon,    ///< point-to-point moves (minimum jerk), some blended, between holds
  kReversals,  ///< constant-speed strokes (0.4-1.5 rad/s) joined by fast reversals (40-150 ms)
  kCreep,      ///< slow motion (5-50 mrad/s) with pauses
  kPalpation,  ///< presses into the tissue and back out, some onto the grasped object
  kReroute,    ///< surgeon-like, with both sheaths' bends changing mid-run
};

std::optional<MotionKind> motion_kind_from_name(std::string_view name);
const char* motion_kind_name(MotionKind kind);
std::vector<MotionKind> all_motion_kinds();

struct PathPoint {
  double x = 0.0, xd = 0.0, xdd = 0.0;
};

/// A motion as knots joined by quintic segments (position, velocity and
/// acceleration continuous), or as an analytic multisine.
class Path {
 public:
  PathPoint at(double t) const;

  struct Knot {
    double t, x, v, a;
  };
  std::vector<Knot> knots;  // for knot paths
  // Multisine: x = fade(t) sum amp_k sin(2 pi f_k t + phase_k).
  std::vector<double> amp, freq, phase;
  double fade_s = 0.0;
};

/// The input pulley's path for `kind` over [0, duration_s] (and a little
/// beyond), drawn from `seed`; palpation aims at `tip`'s surfaces.
Path make_path(MotionKind kind, double duration_s, const TipParams& tip, std::uint64_t seed);

/// The slow external torque on the tip (the grasped tissue pulling), N m,
/// from `seed`: three sines in 0.03-0.25 Hz faded in over 2 s, peak `peak`.
Path make_external_torque(double duration_s, double peak, std::uint64_t seed);

/// The re-route a kReroute run uses, drawn from `seed` (at 12-28 s, each
/// sheath's bends scaled by 0.6-1.5).
Reroute make_reroute(std::uint64_t seed);

}  // namespace tsmh::physics_world
