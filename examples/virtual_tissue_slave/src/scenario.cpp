#include "virtual_tissue_slave/scenario.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <string_view>

namespace tsmh::virtual_tissue_slave {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// 0 -> 1 with zero slope at both ends, for smooth approach and retract moves.
double smoothstep(double u) {
  if (u <= 0.0) return 0.0;
  if (u >= 1.0) return 1.0;
  return 0.5 - 0.5 * std::cos(std::numbers::pi * u);
}

// One palpation: rest, approach and press to `depth` past the surface, hold,
// retract. Alternates a gentle press (stays in the soft layer of the nodule
// preset) with a deep one (reaches the inclusion).
double palpation(double t, double surface) {
  constexpr double kCycle = 5.0, kMove = 1.5, kHold = 1.0;
  constexpr double kRest = -0.1;
  const double cycle = std::floor(t / kCycle);
  const double u = t - cycle * kCycle;
  const double depth = std::fmod(cycle, 2.0) == 0.0 ? 0.08 : 0.3;
  const double target = surface + depth;
  if (u < kMove) return kRest + (target - kRest) * smoothstep(u / kMove);
  if (u < kMove + kHold) return target;
  return target + (kRest - target) * smoothstep((u - kMove - kHold) / kMove);
}

// The excite scenario's reference: a three-sine mix whose amplitude steps
// through 0.05, 0.15, 0.4 and 0.8 rad every 10 s.
double excitation(double t, int joint) {
  // Small strokes matter as much as large ones: a surgeon's gentle motion
  // never leaves the pre-sliding part of the hysteresis.
  constexpr double kLevels[] = {0.05, 0.15, 0.4, 0.8};
  constexpr double kSegment = 10.0;
  const double u = std::fmod(t, 4.0 * kSegment);
  const auto k = static_cast<int>(u / kSegment);
  const double blend = smoothstep((u - k * kSegment) / 1.0);
  const double a = kLevels[(k + 3) % 4] + (kLevels[k] - kLevels[(k + 3) % 4]) * blend;
  const double phase = joint == 0 ? 0.0 : 0.9;
  return a * (0.6 * std::sin(kTwoPi * 0.23 * t + phase) +
              0.3 * std::sin(kTwoPi * 0.61 * t + 1.0 + phase) +
              0.1 * std::sin(kTwoPi * 1.37 * t + 2.0 + phase));
}

// The scenarios, in the order they are listed: each one's defaults.
struct ScenarioDefaults {
  std::string_view name;
  ScenarioKind kind;
  double duration_s;
  std::string_view tissue;
  double surface_rad;
  std::string_view description;
};

constexpr ScenarioDefaults kScenarios[] = {
    {"sine", ScenarioKind::kSine, 30.0, "soft", 0.6,
     "0.8 rad sines (joint1 0.5 Hz, joint2 0.4 Hz) as in the paper's Fig. 2/8/9; "
     "soft tissue at 0.6 rad, touched lightly at the top of each cycle"},
    {"multisine", ScenarioKind::kMultisine, 60.0, "soft", 0.5,
     "sum of four sines (0.13-2.3 Hz, up to 0.8 rad): many speeds and accelerations; "
     "soft tissue at 0.5 rad"},
    {"palpate", ScenarioKind::kPalpate, 40.0, "nodule", 0.2,
     "press the nodule tissue (surface 0.2 rad) every 5 s, alternately gently "
     "(0.08 rad, soft layer) and deeply (0.3 rad, onto the inclusion)"},
    {"chirp", ScenarioKind::kChirp, 60.0, "none", 0.6,
     "0.5 rad chirp 0.1 -> 1.5 Hz over 30 s, repeated; free motion"},
    {"excite", ScenarioKind::kExcite, 40.0, "none", 0.6,
     "identification: a three-sine mix (0.23-1.4 Hz) whose amplitude steps through 0.05, "
     "0.15, 0.4 and 0.8 rad every 10 s, so fits see small strokes as well as large; free motion"},
    {"identify", ScenarioKind::kIdentify, 60.0, "nodule", 0.85,
     "identification on a bench with a tip load cell: 40 s of excite (free motion), then 20 s "
     "of presses into the nodule tissue (surface 0.85 rad, beyond excite's reach), gentle and "
     "deep, so fits see the friction under load"},
};

}  // namespace

std::vector<std::string> scenario_names() {
  std::vector<std::string> names;
  for (const ScenarioDefaults& d : kScenarios)
    names.emplace_back(d.name);
  return names;
}

Scenario make_scenario(std::string_view name) {
  for (const ScenarioDefaults& d : kScenarios) {
    if (d.name != name) continue;
    Scenario s;
    s.kind = d.kind;
    s.name = std::string(d.name);
    s.description = std::string(d.description);
    s.default_duration_s = d.duration_s;
    s.tissue = std::string(d.tissue);
    s.surface_rad = d.surface_rad;
    return s;
  }
  std::string known;
  for (const ScenarioDefaults& d : kScenarios) {
    if (!known.empty()) known += ", ";
    known += d.name;
  }
  throw std::invalid_argument("unknown scenario '" + std::string(name) + "' (known: " + known +
                              ")");
}

double Scenario::reference(double t, int joint) const {
  switch (kind) {
    case ScenarioKind::kSine:
      return 0.8 * std::sin(kTwoPi * (joint == 0 ? 0.5 : 0.4) * t);
    case ScenarioKind::kMultisine: {
      const double phase = joint == 0 ? 0.0 : 1.3;
      return 0.35 * std::sin(kTwoPi * 0.13 * t + phase) +
             0.25 * std::sin(kTwoPi * 0.41 * t + 1.0 + phase) +
             0.15 * std::sin(kTwoPi * 0.97 * t + 2.0 + phase) +
             0.05 * std::sin(kTwoPi * 2.3 * t + 3.0 + phase);
    }
    case ScenarioKind::kPalpate:
      return palpation(joint == 0 ? t : t + 2.5, surface_rad);
    case ScenarioKind::kChirp: {
      constexpr double kSweep = 30.0, kF0 = 0.1, kF1 = 1.5;
      const double u = std::fmod(t, kSweep);
      // Phase of a linear chirp; the amplitude ramps in over the first second
      // of each sweep so the restart is smooth enough for the motor.
      const double phase = kTwoPi * (kF0 * u + 0.5 * (kF1 - kF0) / kSweep * u * u);
      const double ramp = smoothstep(u) * smoothstep((kSweep - u) / 1.0);
      return 0.5 * ramp * std::sin(phase);
    }
    case ScenarioKind::kExcite:
      return excitation(t, joint);
    case ScenarioKind::kIdentify: {
      // Excite, then palpation from its rest phase, blended over 1 s so the
      // reference stays smooth where the two meet.
      constexpr double kFree = 40.0;
      const double press = palpation(t - kFree + 4.0, surface_rad);
      if (t < kFree) return excitation(t, joint);
      const double s = smoothstep(t - kFree);
      return (1.0 - s) * excitation(t, joint) + s * press;
    }
  }
  return 0.0;
}

}  // namespace tsmh::virtual_tissue_slave
