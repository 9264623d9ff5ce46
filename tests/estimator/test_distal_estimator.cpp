#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "estimator/distal_estimator.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

DistalTorqueEstimator paper_estimator(double radius = 0.01) {
  return DistalTorqueEstimator(std::make_unique<TsmFrictionModel>(paper_spec()), radius);
}

TEST(DistalEstimator, EstimateIsProximalTorqueMinusRadiusTimesFriction) {
  auto est = paper_estimator();
  const double w = 2.0 * std::numbers::pi * 0.5;
  for (int i = 0; i < 3000; ++i) {
    const double t = i * 1e-3;
    const double tau_in = 0.2 * std::sin(w * t);
    const auto e = est.update(t, 0.8 * std::sin(w * t), tau_in);
    ASSERT_TRUE(e.valid);
    EXPECT_DOUBLE_EQ(e.tau_in, tau_in);
    EXPECT_DOUBLE_EQ(e.tau_out_est, tau_in - 0.01 * e.friction);
  }
}

TEST(DistalEstimator, TensionsGiveProximalTorqueByEquationOne) {
  auto est = paper_estimator(0.012);
  const auto e = est.update_tensions(0.0, 0.0, 30.0, 12.0);
  EXPECT_DOUBLE_EQ(e.tau_in, 0.012 * (30.0 - 12.0));
}

TEST(DistalEstimator, RejectsBadSamplesWithoutLosingState) {
  auto est = paper_estimator();
  for (int i = 0; i < 500; ++i)
    est.update(i * 1e-3, 0.5 * i * 1e-3, 0.1);
  const auto good = est.update(0.5, 0.25, 0.1);
  ASSERT_TRUE(good.valid);
  const auto nan_tau = est.update(0.501, 0.2505, std::nan(""));
  EXPECT_FALSE(nan_tau.valid);
  EXPECT_TRUE(std::isnan(nan_tau.tau_out_est));
  EXPECT_FALSE(est.update(0.501, std::numeric_limits<double>::infinity(), 0.1).valid);
  EXPECT_FALSE(est.update(0.4, 0.2, 0.1).valid);  // time went backwards
  const auto next = est.update(0.501, 0.2505, 0.1);
  ASSERT_TRUE(next.valid);
  EXPECT_NEAR(next.friction, good.friction, 0.05);
}

TEST(DistalEstimator, ExactDerivativesPath) {
  auto est = paper_estimator();
  Estimate e;
  for (int i = 0; i < 1000; ++i)
    e = est.update_exact(i * 1e-3, 1.0 * i * 1e-3, 1.0, 0.0, 0.0);
  // Sliding forward at 1 rad/s: F -> gamma (rho1 + mu1 e^-kappa1) (lambda term off, xdd = 0).
  EXPECT_NEAR(e.friction, 9.5651 * (1.038 + 1.0978 * std::exp(-6.1264)), 0.05);
}

TEST(DistalEstimator, RefusesBadConfiguration) {
  EXPECT_THROW(DistalTorqueEstimator(nullptr, 0.01), std::invalid_argument);
  EXPECT_THROW(DistalTorqueEstimator(std::make_unique<TsmFrictionModel>(paper_spec()), 0.0),
               std::invalid_argument);
  EXPECT_THROW(
      DistalTorqueEstimator(std::make_unique<TsmFrictionModel>(paper_spec()), std::nan("")),
      std::invalid_argument);
}

TEST(DistalEstimator, ReportsTheSlidingLevelAndHowFarTheFrictionIsFromIt) {
  // The level the friction tends to (gamma Ff) comes with every estimate:
  // the drift monitor tells a saturated friction from one still in its
  // transition by it. At rest (xd = 0, xdd = 0) Ff = rho1 + mu1.
  auto est = paper_estimator();
  const double rest_level = 9.5651 * (1.038 + 1.0978);
  EXPECT_NEAR(est.update(0.0, 0.0, 0.0).friction_level, rest_level, 1e-9);
  // A long stroke one way: |F| climbs to the level and stays there.
  const double v = 0.5;  // rad/s
  Estimate e;
  double min_ratio_late = 1e9, max_ratio_early = 0.0;
  for (int i = 1; i <= 3000; ++i) {
    e = est.update(i * 1e-3, v * i * 1e-3, 0.0);
    ASSERT_TRUE(std::isfinite(e.friction_level));
    ASSERT_GT(e.friction_level, 0.0);
    const double ratio = std::fabs(e.friction) / e.friction_level;
    if (i <= 20) max_ratio_early = std::max(max_ratio_early, ratio);
    if (i >= 2000) min_ratio_late = std::min(min_ratio_late, ratio);
  }
  EXPECT_LT(max_ratio_early, 0.5);  // 10 mrad past the start: still in the transition
  EXPECT_GT(min_ratio_late, 0.95);
  // Models without a level (the baselines) report NaN.
  struct NoLevel final : FrictionDynamics {
    void reset() noexcept override {}
    double step(const Motion&, double) noexcept override { return 0.0; }
    double friction() const noexcept override { return 0.0; }
  };
  EXPECT_TRUE(std::isnan(NoLevel{}.sliding_friction()));
}

}  // namespace
}  // namespace tsmh::estimator

namespace tsmh::estimator {
namespace {

TEST(DistalEstimator, StartsWithTheTipFreeUnlessToldOtherwise) {
  // The sheath holds 5 N of friction at rest (tau_in 0.05 N m, R 0.01 m) when
  // the session starts with the instrument free: the default reads that as
  // friction (tip torque 0); the paper's zero state reads it as tip torque.
  const auto run = [](StartState start) {
    DistalTorqueEstimator est(std::make_unique<TsmFrictionModel>(paper_spec()), 0.01, {}, start);
    Estimate e;
    for (int i = 0; i < 200; ++i)
      e = est.update(i * 1e-3, 0.3, 0.05);
    return e.tau_out_est;
  };
  EXPECT_NEAR(run(StartState::kFreeTip), 0.0, 1e-9);
  EXPECT_NEAR(run(StartState::kZero), 0.05, 1e-9);
  // Beyond what the sheath can hold at rest (gamma Ff = 20.4 N, 0.204 N m)
  // the rest is tip torque.
  DistalTorqueEstimator est(std::make_unique<TsmFrictionModel>(paper_spec()), 0.01);
  const double held = 0.01 * 9.5651 * (1.038 + 1.0978);
  EXPECT_NEAR(est.update(0.0, 0.3, 0.5).tau_out_est, 0.5 - held, 1e-3);
}

}  // namespace
}  // namespace tsmh::estimator
