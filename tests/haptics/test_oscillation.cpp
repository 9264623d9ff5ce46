// OscillationDetector: trips on sustained band energy of the
// rendered torque, never on presses, steps or noise; fades and recovers.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "haptics/oscillation_detector.hpp"

namespace tsmh::haptics {
namespace {

constexpr double kDt = 0.001;
constexpr double kPi = 3.14159265358979323846;

/// A press like the demo's: raised-cosine ramp to `depth` over 1 s, hold.
double press(double t, double depth) {
  if (t < 0.0) return 0.0;
  if (t < 1.0) return depth * 0.5 * (1.0 - std::cos(kPi * t));
  return depth;
}

TEST(OscillationDetector, SustainedOscillationOnAHoldTripsFadesAndRecovers) {
  OscillationDetector d(2, {}, 1000.0);
  double trip_at = -1, zero_at = -1;
  double t = 0;
  for (; t < 3.0; t += kDt) {
    // 0.25 N m hold with a 4 Hz, 0.08 N m ring on joint 0 from t = 1 s.
    const double ring = t >= 1.0 ? 0.08 * std::sin(2 * kPi * 4.0 * t) : 0.0;
    const double g = d.update({0.25 + ring, 0.01}, kDt);
    if (trip_at < 0 && d.tripped()) trip_at = t;
    if (zero_at < 0 && g == 0.0) zero_at = t;
  }
  ASSERT_GT(trip_at, 1.0);
  EXPECT_LT(trip_at, 1.8) << "trips once the band energy builds and two cycles are seen";
  EXPECT_NEAR(zero_at - trip_at, 0.05, 0.0025) << "fades over fade_s";
  EXPECT_EQ(d.trips(), 1U);
  EXPECT_GT(d.band_rms(0), 0.03);
  EXPECT_LT(d.band_rms(1), 1e-3);
  // The ring stops (force is zero now): after hold_s and once quiet, back to
  // full over recover_s.
  double released_at = -1;
  for (double u = 0; u < 3.0; u += kDt) {
    d.update({0.0, 0.0}, kDt);
    if (released_at < 0 && !d.tripped()) released_at = u;
  }
  EXPECT_GE(released_at + t - trip_at, 1.0 - 1e-9) << "held at zero at least hold_s";
  EXPECT_DOUBLE_EQ(d.gain(), 1.0);
  EXPECT_EQ(d.trips(), 1U);
}

TEST(OscillationDetector, PressesStepsAndNoiseNeverTrip) {
  OscillationDetector d(2, {}, 1000.0);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.004);
  double worst = 0;
  for (int rep = 0; rep < 5; ++rep) {
    for (double t = 0; t < 4.0; t += kDt) {
      // Press to 0.27 N m (the demo's deepest), hold, drop at once to 0 (a
      // safety zeroing or a release), plus sensor-like noise.
      const double tau = (t < 2.5 ? press(t, 0.27) : 0.0) + noise(rng);
      EXPECT_DOUBLE_EQ(d.update({tau, -0.5 * tau}, kDt), 1.0) << "t " << t;
      worst = std::max(worst, d.band_rms(0));
    }
  }
  EXPECT_FALSE(d.tripped());
  EXPECT_GT(worst, 0.01) << "the step does raise the band energy; only the crossings hold it off";
}

TEST(OscillationDetector, SmallRingUnderThresholdDoesNotTrip) {
  OscillationDetector d(1, {}, 1000.0);
  for (double t = 0; t < 5.0; t += kDt)
    d.update({0.25 + 0.02 * std::sin(2 * kPi * 6.0 * t)}, kDt);  // rms 0.014 < 0.03
  EXPECT_FALSE(d.tripped());
  EXPECT_NEAR(d.band_rms(0), 0.02 / std::sqrt(2.0), 0.003);
}

TEST(OscillationDetector, NonFiniteInputNeverLatchesAndDisabledPassesThrough) {
  OscillationDetector d(1, {}, 1000.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int i = 0; i < 2000; ++i)
    EXPECT_DOUBLE_EQ(d.update({i % 2 ? nan : std::numeric_limits<double>::infinity()}, kDt), 1.0);
  EXPECT_TRUE(std::isfinite(d.band_rms(0)));
  OscillationConfig off;
  off.enabled = false;
  OscillationDetector o(1, off, 1000.0);
  for (double t = 0; t < 2.0; t += kDt)
    EXPECT_DOUBLE_EQ(o.update({0.2 * std::sin(2 * kPi * 5.0 * t)}, kDt), 1.0);
}

TEST(OscillationDetector, ResetSignalForgetsTheBandEnergy) {
  OscillationDetector d(1, {}, 1000.0);
  for (double t = 0; t < 0.3; t += kDt)
    d.update({0.02 * std::sin(2 * kPi * 5.0 * t)}, kDt);
  EXPECT_GT(d.band_rms(0), 0.0);
  d.reset_signal();
  EXPECT_EQ(d.band_rms(0), 0.0);
}

TEST(OscillationDetector, BadConfigurationNamesTheField) {
  OscillationConfig c;
  c.band_high_hz = 600;
  try {
    OscillationDetector d(1, c, 1000.0);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("safety.oscillation.band_high_hz"), std::string::npos);
  }
  c = {};
  c.threshold_nm = 0;
  EXPECT_THROW(OscillationDetector(1, c, 1000.0), std::invalid_argument);
}

}  // namespace
}  // namespace tsmh::haptics
