#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "master_devices/scenarios.hpp"

namespace tsmh::master_devices {
namespace {

TEST(Scenarios, PalpateTellsTheStoryInAboutTwentySeconds) {
  const PalpateScenario p;
  const Scenario s = p;
  const double T = scenario_duration_s(s);
  EXPECT_GE(T, 18.0);
  EXPECT_LE(T, 22.0);
  EXPECT_EQ(scenario_name(s), "palpate");

  // Deepest intention in each press window: soft presses reach the soft
  // depth, deep presses the hard depth, in that order.
  const int presses = p.soft_presses + p.hard_presses;
  for (int i = 0; i < presses; ++i) {
    const PressWindow w = palpate_press(p, i);
    double deepest = 0;
    for (double t = w.begin_s; t <= w.end_s; t += 0.001) {
      deepest = std::max(deepest, intention_at(s, t, 2).q[p.press_joint]);
    }
    EXPECT_EQ(w.hard, i >= p.soft_presses);
    EXPECT_NEAR(deepest, w.hard ? p.hard_depth_rad : p.soft_depth_rad, 1e-6) << "press " << i;
    // Released between presses.
    EXPECT_NEAR(intention_at(s, w.end_s + 0.5 * p.rest_s, 2).q[p.press_joint], 0.0, 1e-9);
  }
  // Starts and ends at rest; the other joint moves gently.
  EXPECT_EQ(intention_at(s, 0.0, 2).q[0], 0.0);
  EXPECT_NEAR(intention_at(s, 0.0, 2).q[1], 0.0, 1e-12);
  EXPECT_NEAR(intention_at(s, T, 2).q[1], 0.0, 1e-9);
  double other_max = 0;
  for (double t = 0; t < T; t += 0.01)
    other_max = std::max(other_max, std::abs(intention_at(s, t, 2).q[1]));
  EXPECT_GT(other_max, 0.5 * p.other_amplitude_rad);
  EXPECT_LE(other_max, p.other_amplitude_rad + 1e-12);
}

TEST(Scenarios, PalpateVelocityIsTheDerivativeOfPosition) {
  const Scenario s = PalpateScenario{};
  for (double t = 0.5; t < 19.0; t += 0.0371) {
    const double h = 1e-5;
    const double numeric =
        (intention_at(s, t + h, 2).q[0] - intention_at(s, t - h, 2).q[0]) / (2 * h);
    EXPECT_NEAR(intention_at(s, t, 2).qd[0], numeric, 1e-3) << "t " << t;
  }
}

TEST(Scenarios, SineAndStep) {
  SineScenario sine;
  sine.amplitude_rad = {0.2, 0.1};
  sine.frequency_hz = {1.0, 0.5};
  EXPECT_NEAR(intention_at(sine, 0.25, 2).q[0], 0.2, 1e-12);
  EXPECT_NEAR(intention_at(sine, 0.5, 2).q[1], 0.1, 1e-12);
  EXPECT_NEAR(intention_at(sine, 0.0, 2).qd[0], 0.2 * 2 * 3.141592653589793, 1e-9);

  StepScenario step;
  step.amplitude_rad = {0.3, 0.0};
  EXPECT_EQ(intention_at(step, 0.5, 2).q[0], 0.0);
  EXPECT_EQ(intention_at(step, 1.5, 2).q[0], 0.3);
  EXPECT_EQ(intention_at(step, 3.5, 2).q[0], 0.0);
  EXPECT_EQ(intention_at(step, 5.5, 2).q[0], 0.3);
  EXPECT_EQ(scenario_duration_s(step), 1.0 + 4 * 4.0);
  EXPECT_EQ(intention_at(step, 100.0, 2).q[0], 0.0);
}

Scenario parse(const std::string& yaml) {
  config::FieldReader r(YAML::Load(yaml), "server.yaml", "device.settings");
  return parse_scenario(r, 2);
}

std::string error_of(const std::string& yaml) {
  try {
    parse(yaml);
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

// The re-route demo's scenario: presses alternate, and after the
// fourth every joint sweeps in free space (away from the tissue) while the
// recalibration button is pressed once for 0.2 s.
TEST(Scenarios, PalpateSweepWithTheRecalibrationButton) {
  PalpateScenario p;
  p.soft_presses = 3;
  p.hard_presses = 3;
  p.alternate = true;
  p.sweep.after_press = 4;
  const Scenario s = p;
  const double plain = 1.0 + 6 * (1.0 + 0.6 + 0.8 + 1.0) + 2.0;
  EXPECT_NEAR(scenario_duration_s(s), plain + p.sweep.duration_s, 1e-9);
  for (int i = 0; i < 6; ++i) {
    const PressWindow w = palpate_press(p, i);
    EXPECT_EQ(w.hard, i % 2 == 1) << i;
    double deepest = 0;
    for (double t = w.begin_s; t <= w.end_s; t += 0.001)
      deepest = std::max(deepest, intention_at(s, t, 2).q[0]);
    EXPECT_NEAR(deepest, w.hard ? p.hard_depth_rad : p.soft_depth_rad, 1e-6) << "press " << i;
  }
  const double begin = palpate_press(p, 3).end_s + p.rest_s;
  EXPECT_NEAR(palpate_press(p, 4).begin_s, begin + p.sweep.duration_s, 1e-9);
  double lowest0 = 0, lowest1 = 0, highest = -1, pressed_s = 0;
  for (double t = begin; t < begin + p.sweep.duration_s; t += 0.001) {
    const Intention in = intention_at(s, t, 2);
    lowest0 = std::min(lowest0, in.q[0]);
    lowest1 = std::min(lowest1, in.q[1]);
    highest = std::max({highest, in.q[0], in.q[1]});
    if (in.calibrate) pressed_s += 0.001;
  }
  EXPECT_LT(lowest0, -1.5 * p.sweep.amplitude_rad);  // a real stroke, every joint
  EXPECT_LT(lowest1, -1.5 * p.sweep.amplitude_rad);
  EXPECT_LE(highest, 1e-12);  // never towards the tissue
  EXPECT_NEAR(pressed_s, 0.2, 0.002);
  EXPECT_FALSE(intention_at(s, begin - 0.1, 2).calibrate);
  // Smooth: velocity is the derivative of position through the sweep.
  for (double t = begin + 0.013; t < begin + p.sweep.duration_s; t += 0.0371) {
    const double h = 1e-5;
    const double numeric =
        (intention_at(s, t + h, 2).q[1] - intention_at(s, t - h, 2).q[1]) / (2 * h);
    EXPECT_NEAR(intention_at(s, t, 2).qd[1], numeric, 2e-3) << "t " << t;
  }
  EXPECT_NE(error_of("palpate: {sweep: {after_press: 9}}\n").find("palpate.sweep.after_press"),
            std::string::npos);
}

TEST(Scenarios, ParsesSettingsAndNamesBadFields) {
  const Scenario p = parse("scenario: palpate\npalpate: {soft_depth_rad: 0.1, hard_presses: 3}\n");
  ASSERT_TRUE(std::holds_alternative<PalpateScenario>(p));
  EXPECT_EQ(std::get<PalpateScenario>(p).soft_depth_rad, 0.1);
  EXPECT_EQ(std::get<PalpateScenario>(p).hard_presses, 3);
  EXPECT_EQ(std::get<PalpateScenario>(p).press_joint, 0u);  // joint1 by default
  // The pressing joint by its name, or by the 0-based index earlier configs gave.
  EXPECT_EQ(std::get<PalpateScenario>(parse("palpate: {press_joint: joint2}\n")).press_joint, 1u);
  EXPECT_EQ(std::get<PalpateScenario>(parse("palpate: {press_joint: 1}\n")).press_joint, 1u);
  const Scenario s = parse("scenario: sine\nsine: {amplitude_rad: [0.1, 0.2], frequency_hz: 2}\n");
  ASSERT_TRUE(std::holds_alternative<SineScenario>(s));
  EXPECT_EQ(std::get<SineScenario>(s).amplitude_rad[1], 0.2);
  EXPECT_EQ(std::get<SineScenario>(s).frequency_hz[0], 2.0);

  EXPECT_NE(error_of("scenario: knead\n")
                .find("server.yaml: device.settings.scenario: unknown scenario 'knead'"),
            std::string::npos);
  EXPECT_NE(error_of("palpate: {hard_depth_rad: 0.1}\n")
                .find("device.settings.palpate.hard_depth_rad: must be > soft_depth_rad"),
            std::string::npos);
  EXPECT_NE(error_of("palpate: {press_joint: 2}\n")
                .find("palpate.press_joint: must name a joint: joint1 .. joint2"),
            std::string::npos);
  EXPECT_NE(error_of("palpate: {press_joint: joint3}\n")
                .find("palpate.press_joint: must name a joint: joint1 .. joint2"),
            std::string::npos);
  EXPECT_NE(error_of("scenario: sine\nsine: {amplitude_rad: [1, 2, 3]}\n")
                .find("sine.amplitude_rad: must be a number or a list of 2 numbers"),
            std::string::npos);
  EXPECT_NE(error_of("scenario: step\nstep: {hgh_s: 1}\n").find("step.hgh_s: unknown key"),
            std::string::npos);
}

TEST(Scenarios, EachNameParsesToItsScenarioAndTheOthersSectionsAreKnownKeys) {
  for (const char* name : {"palpate", "sine", "step"}) {
    // Every scenario's section may stand beside the chosen one: none is unknown.
    config::FieldReader r(YAML::Load(std::string("scenario: ") + name +
                                     "\npalpate: {hard_presses: 2}\nsine: {duration_s: 3}\n"
                                     "step: {repeats: 4}\n"),
                          "server.yaml", "device.settings");
    const Scenario s = parse_scenario(r, 2);
    EXPECT_NO_THROW(r.reject_unknown()) << name;
    EXPECT_EQ(scenario_name(s), name);
  }
  EXPECT_EQ(std::get<StepScenario>(parse("scenario: step\nstep: {repeats: 4}\n")).repeats, 4);
  // A nested section's errors name the file and the whole path.
  EXPECT_NE(error_of("palpate: {sweep: {after_press: 1, duration_s: 1}}\n")
                .find("server.yaml: device.settings.palpate.sweep.duration_s: must be >= 2"),
            std::string::npos)
      << error_of("palpate: {sweep: {after_press: 1, duration_s: 1}}\n");
}

}  // namespace
}  // namespace tsmh::master_devices
