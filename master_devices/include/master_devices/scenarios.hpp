#pragma once
// Scripted operator intentions: where the simulated operator *wants* the
// handle to be, as a function of time. The hand model (simulated_operator.hpp)
// follows this intention through its own stiffness, so rendered torque
// pushes the hand away from it.
//
// palpate: the demo's story. The slave tool rests above tissue made of a
//   soft layer over a hard nodule. The operator presses gently a few times
//   on the pressing joint (shallow: only the soft layer, feels soft), then
//   presses deeper a few times (into the nodule, feels hard). The other
//   joint makes a slow, gentle sweep. About 20 s with the defaults.
// sine:    independent sinusoids per joint.
// step:    steps to an amplitude and back, repeated.

#include <cstddef>
#include <string_view>
#include <variant>

#include "config/field_reader.hpp"
#include "master_devices/types.hpp"

namespace tsmh::master_devices {

/// A free-motion sweep of every joint between two presses, with the
/// recalibration button pressed during it (the re-route demo).
struct PalpateSweep {
  int after_press = -1;        ///< the sweep follows this many presses; -1: none
  double duration_s = 8.0;     ///< including a 1 s fade in and out
  double amplitude_rad = 0.4;  ///< swept away from the tissue: 0 .. -2 amplitude
  double frequency_hz = 0.6;
  double button_at_s = 0.5;  ///< the calibrate button, 0.2 s, this long into the sweep; < 0 never
};

struct PalpateScenario {
  std::size_t press_joint = 0;  ///< the joint that presses into the tissue
  double press_sign = 1.0;      ///< +1: pressing is positive joint angle
  int soft_presses = 3;
  double soft_depth_rad = 0.15;  ///< intention depth of a gentle press (soft layer only)
  int hard_presses = 2;
  double hard_depth_rad = 0.40;       ///< intention depth of a deep press (into the nodule)
  double start_s = 1.0;               ///< rest before the first press
  double press_s = 1.0;               ///< smooth ramp in
  double hold_s = 0.6;                ///< hold at depth
  double release_s = 0.8;             ///< smooth ramp out
  double rest_s = 1.0;                ///< pause between presses
  double end_s = 2.0;                 ///< rest after the last press
  double other_amplitude_rad = 0.05;  ///< gentle sweep of the other joint(s)
  double other_frequency_hz = 0.2;
  /// Soft and hard presses alternate (soft first) instead of all soft, then all hard.
  bool alternate = false;
  PalpateSweep sweep{};
};

struct SineScenario {
  JointArray amplitude_rad{0.3, 0.2};
  JointArray frequency_hz{0.5, 0.3};
  JointArray phase_rad{};
  JointArray offset_rad{};
  double duration_s = 20.0;
};

struct StepScenario {
  JointArray amplitude_rad{0.3, 0.0};
  double start_s = 1.0;  ///< rest before the first step
  double high_s = 2.0;   ///< time at the amplitude
  double low_s = 2.0;    ///< time back at zero
  int repeats = 4;
};

using Scenario = std::variant<PalpateScenario, SineScenario, StepScenario>;

/// Where the operator wants the handle, and how fast it wants it to move.
struct Intention {
  JointArray q{};
  JointArray qd{};
  bool calibrate = false;  ///< the operator presses the recalibration button
};

/// The intention at scenario time t_s (>= 0) for joints 0 .. dof-1; after
/// the scenario's end it holds its final value.
Intention intention_at(const Scenario& s, double t_s, std::size_t dof);
/// Length of the scenario, s.
double scenario_duration_s(const Scenario& s);
/// "palpate", "sine" or "step".
std::string_view scenario_name(const Scenario& s);
/// Time windows of the palpate presses: start of ramp-in and end of ramp-out
/// for press i (0-based), and whether it is a deep (hard) press.
struct PressWindow {
  double begin_s = 0.0;
  double end_s = 0.0;
  bool hard = false;
};
PressWindow palpate_press(const PalpateScenario& p, int index);

/// Reads `scenario: NAME` plus the optional map under the same name
/// (e.g. `palpate: {soft_depth_rad: 0.1}`) from a driver settings map.
Scenario parse_scenario(config::FieldReader& settings, std::size_t dof);

}  // namespace tsmh::master_devices
