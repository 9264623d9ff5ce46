// Integration of eq. (4): exact solutions where they exist, a fine-step
// reference at 1 kHz and at irregular intervals, and boundedness.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "estimator/bouc_wen_state.hpp"
#include "estimator/simulate.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

constexpr BoucWenShape kPaperShape{1.0, 2.0, 1.0};

TEST(BoucWenState, RateIsEquationFourAsPrinted) {
  // theta g (1 - |w|^n + sigma |w|^(n-1) (sgn w - sgn g) w), w = z/Ff
  const BoucWenShape s{15.5181, 2.0, 1.0};
  const double z = 0.3, ff = 1.2, g = -0.7;
  const double w = z / ff;
  const double expected = 15.5181 * g * (1.0 - w * w + 1.0 * w * (1.0 - -1.0) * w);
  EXPECT_NEAR(bouc_wen_rate(z, ff, g, s), expected, 1e-12);
}

TEST(BoucWenState, LoadingFollowsTanhForPaperShape) {
  // n = 2, sigma = 1, same direction: du/da = 1 - u^2, so u = tanh(a).
  for (double a : {0.01, 0.1, 0.5, 2.0, 5.0}) {
    EXPECT_NEAR(advance_bouc_wen_state(0.0, 1.0, 1.0, a, kPaperShape), std::tanh(a), 2e-6) << a;
    EXPECT_NEAR(advance_bouc_wen_state(0.0, 2.0, -1.0, 2.0 * a, kPaperShape), -2.0 * std::tanh(a),
                4e-6);
  }
}

TEST(BoucWenState, UnloadingFollowsTanForPaperShape) {
  // Opposite direction: du/da = 1 + u^2 until u = 0, u = tan(atan(u0) + a).
  const double u0 = -0.5, a = 0.3;
  EXPECT_NEAR(advance_bouc_wen_state(u0, 1.0, 1.0, a, kPaperShape), std::tan(std::atan(u0) + a),
              2e-6);
}

TEST(BoucWenState, StaysBetweenStartAndFixedPointForAnyInterval) {
  for (double dt : {1e-3, 0.05, 1.0, 100.0, 1e6}) {
    const double z = advance_bouc_wen_state(-0.9, 1.0, 3.0, dt, {15.5, 2.0, 1.0});
    EXPECT_GE(z, -0.9);
    EXPECT_LE(z, 1.0);
    // Level dropped below the state: decays towards Ff, never below it.
    const double z2 = advance_bouc_wen_state(3.0, 1.0, 3.0, dt, {15.5, 2.0, 1.0});
    EXPECT_LE(z2, 3.0);
    EXPECT_GE(z2, 1.0);
  }
  EXPECT_DOUBLE_EQ(advance_bouc_wen_state(0.4, 1.0, 0.0, 1.0, kPaperShape),
                   0.4);  // g = 0: no change
}

// Sine input with exact derivatives at arbitrary times.
Motion sine_motion(double t) {
  const double w = 2.0 * std::numbers::pi * 0.5;
  const double xdd = -0.8 * w * w * std::sin(w * t);
  return {t, 0.8 * std::sin(w * t), 0.8 * w * std::cos(w * t), xdd, sign_of(xdd), 0.0};
}

// Eq. (4) integrated literally with RK4 at 10 us, inputs evaluated continuously.
std::vector<double> reference_friction(const std::vector<double>& times) {
  const TsmFrictionModel model(paper_spec());
  const auto& spec = model.spec();
  const BoucWenShape shape{spec.theta, spec.n, spec.sigma};
  const auto rate = [&](double t, double z) {
    const Motion m = sine_motion(t);
    return bouc_wen_rate(z, model.sliding_level(m), model.drive(m.xd, m.acc_sign), shape);
  };
  std::vector<double> f;
  double z = 0.0, t = times.front();
  const double h = 1e-5;
  for (double target : times) {
    while (t < target - 1e-12) {
      const double step = std::min(h, target - t);
      const double k1 = rate(t, z), k2 = rate(t + step / 2, z + step / 2 * k1);
      const double k3 = rate(t + step / 2, z + step / 2 * k2), k4 = rate(t + step, z + step * k3);
      z += step / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      t += step;
    }
    f.push_back(spec.gamma * z);
  }
  return f;
}

double max_abs_error_after(const std::vector<double>& times, double t0) {
  std::vector<Motion> motion;
  for (double t : times)
    motion.push_back(sine_motion(t));
  TsmFrictionModel model(paper_spec());
  const auto f = simulate_friction(model, motion);
  const auto ref = reference_friction(times);
  double worst = 0.0;
  for (std::size_t i = 0; i < times.size(); ++i)
    if (times[i] >= t0) worst = std::max(worst, std::fabs(f[i] - ref[i]));
  return worst;
}

TEST(BoucWenState, MatchesFineStepReferenceAt1kHz) {
  std::vector<double> times;
  for (int i = 0; i <= 6000; ++i)
    times.push_back(i * 1e-3);
  const double err = max_abs_error_after(times, 1.0);
  RecordProperty("max_abs_error_N", std::to_string(err));
  // The loop spans about 18.8 N; 1 kHz sampling holds it within 0.1 N (0.5 %).
  EXPECT_LT(err, 0.1);
}

TEST(BoucWenState, MatchesFineStepReferenceWithIrregularIntervalsAndDrops) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(0.5e-3, 1.5e-3);
  std::uniform_int_distribution<int> drop(0, 99);
  std::vector<double> times{0.0};
  while (times.back() < 6.0) {
    double dt = jitter(rng);
    if (drop(rng) == 0) dt += 0.02 + 0.03 * (drop(rng) / 99.0);  // dropped packets: 20-50 ms gaps
    times.push_back(times.back() + dt);
  }
  const double err = max_abs_error_after(times, 1.0);
  RecordProperty("max_abs_error_N", std::to_string(err));
  EXPECT_LT(err, 0.6);
}

TEST(BoucWenState, BoundedForAnHourOfRandomInput) {
  TsmFrictionModel model(paper_spec());
  std::mt19937 rng(42);
  std::normal_distribution<double> accel(0.0, 40.0);
  std::uniform_real_distribution<double> jitter(0.2e-3, 3e-3);
  std::uniform_int_distribution<int> rare(0, 9999);
  double t = 0.0, x = 0.0, xd = 0.0, worst = 0.0;
  const double bound = paper_spec().gamma * (1.038 + 1.0978 + 0.0458 + 0.145);  // gamma * max Ff
  while (t < 3600.0) {
    double dt = jitter(rng);
    if (rare(rng) == 0) dt = 0.5;                        // occasional long gap
    const double xdd = accel(rng) - 2.0 * xd - 5.0 * x;  // random but physically bounded motion
    xd += xdd * dt;
    x += xd * dt;
    t += dt;
    Motion m{t, x, xd, xdd, sign_of(xdd), 0.0};
    if (rare(rng) == 1) m.xd = std::nan("");  // hostile sample: must be ignored
    const double f = model.step(m, dt);
    ASSERT_TRUE(std::isfinite(f)) << "t=" << t;
    worst = std::max(worst, std::fabs(f));
  }
  RecordProperty("max_abs_F_N", std::to_string(worst));
  EXPECT_LE(worst, bound + 1e-9);
  EXPECT_GT(worst, 5.0);  // the input did drive the model into sliding
}

}  // namespace
}  // namespace tsmh::estimator
