#include "master_devices/scenarios.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <variant>

#include "realtime/joint_names.hpp"

namespace tsmh::master_devices {
namespace {

constexpr double kPi = std::numbers::pi;

// Smooth 0 -> 1 over [0, T] (raised cosine) and its time derivative.
double ramp(double t, double T) {
  if (t <= 0.0) return 0.0;
  if (t >= T) return 1.0;
  return 0.5 - 0.5 * std::cos(kPi * t / T);
}
double ramp_rate(double t, double T) {
  if (t <= 0.0 || t >= T) return 0.0;
  return 0.5 * kPi / T * std::sin(kPi * t / T);
}

double press_period(const PalpateScenario& p) {
  return p.press_s + p.hold_s + p.release_s + p.rest_s;
}

bool has_sweep(const PalpateScenario& p) {
  return p.sweep.after_press >= 0 && p.sweep.after_press <= p.soft_presses + p.hard_presses;
}

// Where press `index` begins, after the sweep when it comes later.
double press_begin(const PalpateScenario& p, int index) {
  const double shift = has_sweep(p) && index >= p.sweep.after_press ? p.sweep.duration_s : 0.0;
  return p.start_s + index * press_period(p) + shift;
}

bool is_hard(const PalpateScenario& p, int index) {
  if (p.alternate) {
    // soft, hard, soft, ... while both kinds remain; then the rest of either
    const int pairs = std::min(p.soft_presses, p.hard_presses);
    if (index < 2 * pairs) return index % 2 == 1;
    return p.hard_presses > p.soft_presses;
  }
  return index >= p.soft_presses;
}

// The free-motion sweep of every joint (a recalibration needs them all to
// move): away from the tissue (against press_sign), faded in and out over
// 1 s, the button pressed 0.2 s at button_at_s.
bool sweep_intention(const PalpateScenario& p, double t, std::size_t dof, Intention& in) {
  if (!has_sweep(p)) return false;
  const double begin = p.start_s + p.sweep.after_press * press_period(p);
  const double u = t - begin;
  if (u < 0.0 || u >= p.sweep.duration_s) return false;
  const double w = 2.0 * kPi * p.sweep.frequency_hz;
  const double out_u = u - (p.sweep.duration_s - 1.0);
  const double fade = ramp(u, 1.0) * (1.0 - ramp(out_u, 1.0));
  const double fade_rate =
      ramp_rate(u, 1.0) * (1.0 - ramp(out_u, 1.0)) - ramp(u, 1.0) * ramp_rate(out_u, 1.0);
  const double a = p.sweep.amplitude_rad;
  // -a (1 - cos): starts at 0 with zero velocity, swings to -2a and back.
  for (std::size_t j = 0; j < dof && j < kMaxDof; ++j) {
    in.q[j] = -p.press_sign * fade * a * (1.0 - std::cos(w * u));
    in.qd[j] =
        -p.press_sign * a * (fade_rate * (1.0 - std::cos(w * u)) + fade * w * std::sin(w * u));
  }
  in.calibrate =
      p.sweep.button_at_s >= 0.0 && u >= p.sweep.button_at_s && u < p.sweep.button_at_s + 0.2;
  return true;
}

Intention palpate(const PalpateScenario& p, double t, std::size_t dof) {
  Intention in;
  const int presses = p.soft_presses + p.hard_presses;
  const bool sweeping = sweep_intention(p, t, dof, in);
  int index = 0;
  while (index + 1 < presses && t >= press_begin(p, index + 1))
    ++index;
  const double local = t - press_begin(p, index);
  if (!sweeping && local >= 0.0 && presses > 0) {
    const double depth = is_hard(p, index) ? p.hard_depth_rad : p.soft_depth_rad;
    double x = 0.0;
    double xd = 0.0;
    if (local < p.press_s) {
      x = ramp(local, p.press_s);
      xd = ramp_rate(local, p.press_s);
    } else if (local < p.press_s + p.hold_s) {
      x = 1.0;
    } else {
      const double r = local - p.press_s - p.hold_s;
      x = 1.0 - ramp(r, p.release_s);
      xd = -ramp_rate(r, p.release_s);
    }
    in.q[p.press_joint] = p.press_sign * depth * x;
    in.qd[p.press_joint] = p.press_sign * depth * xd;
  }
  const double w = 2.0 * kPi * p.other_frequency_hz;
  const double end = scenario_duration_s(p);
  // Fade the sweep in and out so the hand starts and ends at rest.
  const double fade = ramp(t, 1.0) * (1.0 - ramp(t - (end - 1.0), 1.0));
  for (std::size_t j = 0; j < dof && j < kMaxDof && !sweeping; ++j) {
    if (j == p.press_joint) continue;
    in.q[j] = fade * p.other_amplitude_rad * std::sin(w * t);
    in.qd[j] = fade * p.other_amplitude_rad * w * std::cos(w * t);
  }
  return in;
}

Intention sine(const SineScenario& s, double t, std::size_t dof) {
  Intention in;
  for (std::size_t j = 0; j < dof && j < kMaxDof; ++j) {
    const double w = 2.0 * kPi * s.frequency_hz[j];
    in.q[j] = s.offset_rad[j] + s.amplitude_rad[j] * std::sin(w * t + s.phase_rad[j]);
    in.qd[j] = s.amplitude_rad[j] * w * std::cos(w * t + s.phase_rad[j]);
  }
  return in;
}

Intention step(const StepScenario& s, double t, std::size_t dof) {
  Intention in;
  const double u = t - s.start_s;
  const double period = s.high_s + s.low_s;
  const bool high = u >= 0.0 && u < period * s.repeats && std::fmod(u, period) < s.high_s;
  for (std::size_t j = 0; j < dof && j < kMaxDof; ++j)
    in.q[j] = high ? s.amplitude_rad[j] : 0.0;
  return in;  // a true step: qd stays 0, the hand's own dynamics smooth it
}

int count(config::FieldReader& r, std::string_view key, int fallback) {
  const long long v = r.get_int(key, fallback);
  if (v < 0 || v > 1000) r.fail(key, "must be 0 .. 1000");
  return static_cast<int>(v);
}

Scenario parse_palpate(config::FieldReader& r, std::size_t dof) {
  PalpateScenario p;
  // The joint's name, as everywhere else; the 0-based index earlier
  // configs gave is taken too.
  const auto joint = realtime::joint_from_text(r.get_string("press_joint", "joint1"), dof);
  if (!joint) {
    r.fail("press_joint", "must name a joint: joint1 .. " + realtime::joint_name(dof - 1) +
                              " (or its 0-based index 0 .. " + std::to_string(dof - 1) + ")");
  }
  p.press_joint = joint.value_or(0);
  p.press_sign = r.get_double("press_sign", 1.0);
  if (p.press_sign != 1.0 && p.press_sign != -1.0) r.fail("press_sign", "must be 1 or -1");
  p.soft_presses = count(r, "soft_presses", p.soft_presses);
  p.soft_depth_rad = r.get_positive("soft_depth_rad", p.soft_depth_rad);
  p.hard_presses = count(r, "hard_presses", p.hard_presses);
  p.hard_depth_rad = r.get_positive("hard_depth_rad", p.hard_depth_rad);
  if (p.hard_presses > 0 && p.soft_presses > 0 && !(p.hard_depth_rad > p.soft_depth_rad)) {
    r.fail("hard_depth_rad", "must be > soft_depth_rad (the nodule lies below the soft layer)");
  }
  p.start_s = r.get_non_negative("start_s", p.start_s);
  p.press_s = r.get_positive("press_s", p.press_s);
  p.hold_s = r.get_non_negative("hold_s", p.hold_s);
  p.release_s = r.get_positive("release_s", p.release_s);
  p.rest_s = r.get_non_negative("rest_s", p.rest_s);
  p.end_s = r.get_non_negative("end_s", p.end_s);
  p.other_amplitude_rad = r.get_non_negative("other_amplitude_rad", p.other_amplitude_rad);
  p.other_frequency_hz = r.get_non_negative("other_frequency_hz", p.other_frequency_hz);
  p.alternate = r.get_bool("alternate", false);
  const YAML::Node sweep_node = r.node("sweep");
  if (sweep_node) {
    config::FieldReader sw(sweep_node, r.source(), r.field("sweep"));
    p.sweep.after_press = count(sw, "after_press", 0);
    if (p.sweep.after_press > p.soft_presses + p.hard_presses)
      sw.fail("after_press", "must be at most the number of presses");
    p.sweep.duration_s = sw.get_positive("duration_s", p.sweep.duration_s);
    if (p.sweep.duration_s < 2.0) sw.fail("duration_s", "must be >= 2 (1 s fades)");
    p.sweep.amplitude_rad = sw.get_positive("amplitude_rad", p.sweep.amplitude_rad);
    p.sweep.frequency_hz = sw.get_positive("frequency_hz", p.sweep.frequency_hz);
    p.sweep.button_at_s = sw.get_double("button_at_s", p.sweep.button_at_s);
    sw.reject_unknown();
  }
  return p;
}

Scenario parse_sine(config::FieldReader& r, std::size_t dof) {
  SineScenario s;
  r.get_joint_array("amplitude_rad", s.amplitude_rad, dof);
  r.get_joint_array("frequency_hz", s.frequency_hz, dof);
  r.get_joint_array("phase_rad", s.phase_rad, dof);
  r.get_joint_array("offset_rad", s.offset_rad, dof);
  s.duration_s = r.get_positive("duration_s", s.duration_s);
  return s;
}

Scenario parse_step(config::FieldReader& r, std::size_t dof) {
  StepScenario s;
  r.get_joint_array("amplitude_rad", s.amplitude_rad, dof);
  s.start_s = r.get_non_negative("start_s", s.start_s);
  s.high_s = r.get_positive("high_s", s.high_s);
  s.low_s = r.get_positive("low_s", s.low_s);
  s.repeats = count(r, "repeats", s.repeats);
  return s;
}

// The scenarios in the Scenario variant's order: the name settings and
// reports use, and the parser of its settings section.
struct ScenarioKind {
  std::string_view name;
  Scenario (*parse)(config::FieldReader& section, std::size_t dof);
};
constexpr ScenarioKind kScenarios[] = {
    {"palpate", parse_palpate}, {"sine", parse_sine}, {"step", parse_step}};
static_assert(std::size(kScenarios) == std::variant_size_v<Scenario>);

}  // namespace

PressWindow palpate_press(const PalpateScenario& p, int index) {
  const double begin = press_begin(p, index);
  return PressWindow{begin, begin + p.press_s + p.hold_s + p.release_s, is_hard(p, index)};
}

Intention intention_at(const Scenario& s, double t_s, std::size_t dof) {
  const double t = std::max(0.0, t_s);
  return std::visit(
      [&](const auto& sc) -> Intention {
        using T = std::decay_t<decltype(sc)>;
        if constexpr (std::is_same_v<T, PalpateScenario>) return palpate(sc, t, dof);
        if constexpr (std::is_same_v<T, SineScenario>) return sine(sc, t, dof);
        if constexpr (std::is_same_v<T, StepScenario>) return step(sc, t, dof);
      },
      s);
}

double scenario_duration_s(const Scenario& s) {
  return std::visit(
      [](const auto& sc) -> double {
        using T = std::decay_t<decltype(sc)>;
        if constexpr (std::is_same_v<T, PalpateScenario>) {
          return sc.start_s + (sc.soft_presses + sc.hard_presses) * press_period(sc) +
                 (has_sweep(sc) ? sc.sweep.duration_s : 0.0) + sc.end_s;
        }
        if constexpr (std::is_same_v<T, SineScenario>) return sc.duration_s;
        if constexpr (std::is_same_v<T, StepScenario>) {
          return sc.start_s + sc.repeats * (sc.high_s + sc.low_s);
        }
      },
      s);
}

std::string_view scenario_name(const Scenario& s) {
  return kScenarios[s.index()].name;
}

Scenario parse_scenario(config::FieldReader& settings, std::size_t dof) {
  const std::string name = settings.get_string("scenario", "palpate");
  // Read every scenario's map key so that e.g. a `sine:` block next to
  // `scenario: palpate` is not reported as unknown, but only parse the chosen one.
  std::array<YAML::Node, std::size(kScenarios)> sections;
  for (std::size_t k = 0; k < sections.size(); ++k)
    sections[k] = settings.node(kScenarios[k].name);
  for (std::size_t k = 0; k < sections.size(); ++k) {
    if (name != kScenarios[k].name) continue;
    config::FieldReader r(sections[k], settings.source(), settings.field(name));
    Scenario scenario = kScenarios[k].parse(r, dof);
    r.reject_unknown();
    return scenario;
  }
  settings.fail("scenario", "unknown scenario '" + name + "' (expected palpate, sine or step)");
}

}  // namespace tsmh::master_devices
