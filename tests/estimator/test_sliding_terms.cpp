// Eqs. (5)-(11) against values computed by hand (python, from the printed
// equations) in every branch, including the boundaries xd = 0 and xdd = 0.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

double level(double xd, double xdd) {
  const TsmFrictionModel model(paper_spec());
  return model.sliding_level(Motion{.xd = xd, .xdd = xdd, .acc_sign = sign_of(xdd)});
}

TEST(SlidingLevel, PositiveVelocityAccelerating_Eq6) {
  EXPECT_NEAR(level(0.5, 2.0), 1.091707790653388, 1e-12);
}

TEST(SlidingLevel, PositiveVelocityDecelerating_Eq7) {
  EXPECT_NEAR(level(0.5, -2.0), 1.0869099303009553, 1e-12);
}

TEST(SlidingLevel, PositiveVelocityZeroAcceleration_Eq6EqualsEq7) {
  // xdd = 0 belongs to both (6) and (7); the mu2 term vanishes there.
  EXPECT_NEAR(level(0.5, 0.0), 1.0893088604771717, 1e-12);
  EXPECT_NEAR(level(0.5, 1e-12), level(0.5, -1e-12), 1e-12);
}

TEST(SlidingLevel, ZeroVelocityTakesPositiveBranch) {
  // Boundary rule: xd = 0 uses S+v (rho1), not S-v (rho2).
  EXPECT_NEAR(level(0.0, 3.0), 2.1393508560896852, 1e-12);
  EXPECT_NEAR(level(0.0, 0.0), 1.038 + 1.0978, 1e-12);
  EXPECT_GT(level(0.0, 0.0) - level(-1e-9, 0.0), 0.14);  // rho1 - rho2 = 0.1476
}

TEST(SlidingLevel, NegativeVelocityDecelerating_Eq9) {
  // xd < 0, xdd < 0: S-v1 with +mu3 (eq. 9), not the "+ sgn(xdd)" of eq. (8).
  EXPECT_NEAR(level(-0.5, -2.0), 1.0052569111080385, 1e-12);
}

TEST(SlidingLevel, NegativeVelocityAccelerating_Eq10) {
  EXPECT_NEAR(level(-0.5, 2.0), 0.8781608098463048, 1e-12);
}

TEST(SlidingLevel, NegativeVelocityZeroAcceleration_Eq11) {
  EXPECT_NEAR(level(-0.5, 0.0), 0.9417088604771716, 1e-12);
}

TEST(SlidingLevel, FastNegativeMotion) {
  EXPECT_NEAR(level(-2.0, 5.0), 0.8772805834324865, 1e-12);
}

TEST(SlidingLevel, UsesDebouncedSignNotRawAcceleration) {
  // The branch follows acc_sign (the differentiator's debounced sgn(xdd));
  // the magnitude |xdd| still scales the term.
  const TsmFrictionModel model(paper_spec());
  const double with_plus = model.sliding_level(Motion{.xd = 0.5, .xdd = -2.0, .acc_sign = +1});
  EXPECT_NEAR(with_plus, 1.091707790653388, 1e-12);
}

TEST(SlidingLevel, FlooredAtMinimum) {
  TsmModelSpec spec = dahl_spec();
  spec.add(TermKind::kLoadDependent).p = {-1.0};
  const TsmFrictionModel model(spec);
  EXPECT_DOUBLE_EQ(model.sliding_level(Motion{.xd = 1.0, .load = 100.0}), kMinSlidingLevel);
}

TEST(SlidingLevel, LevelScaleMultipliesFfAndLeavesTheState) {
  TsmFrictionModel model(paper_spec());
  const Motion m{.t = 0.0, .x = 0.0, .xd = 0.5, .xdd = 0.0, .acc_sign = 0.0, .load = 0.0};
  const double ff = model.sliding_level(m);
  for (int i = 0; i < 100; ++i)
    model.step(m, 1e-3);
  const double f = model.friction();
  ASSERT_TRUE(model.set_level_scale(1.5));
  EXPECT_EQ(model.friction(), f);  // the state stays: no jump
  EXPECT_DOUBLE_EQ(model.sliding_level(m), 1.5 * ff);
  model.reset();
  EXPECT_DOUBLE_EQ(model.sliding_level(m), 1.5 * ff);  // configuration, kept by reset()
  for (double bad : {0.0, -1.0, std::nan(""), static_cast<double>(INFINITY)})
    EXPECT_FALSE(model.set_level_scale(bad)) << bad;
  EXPECT_DOUBLE_EQ(model.level_scale(false), 1.5);
  // Each direction its own: the negative branch at 0.8.
  ASSERT_TRUE(model.set_level_scales(1.5, 0.8));
  Motion back = m;
  back.xd = -0.5;
  TsmFrictionModel plain(paper_spec());
  EXPECT_DOUBLE_EQ(model.sliding_level(back), 0.8 * plain.sliding_level(back));
  EXPECT_DOUBLE_EQ(model.sliding_level(m), 1.5 * ff);
}

TEST(SlidingTerms, CatalogNamesAreStableAndUnique) {
  const char* expected[] = {"coulomb",
                            "direction_asymmetry",
                            "stribeck",
                            "acceleration_dependence",
                            "reversal_offset",
                            "viscous",
                            "load_dependent",
                            "position_dependent",
                            "time_varying",
                            "position_ripple",
                            "position_bump",
                            "load_saturating",
                            "hysteresis_elements",
                            "load_scaling",
                            "tension_scaling"};
  ASSERT_EQ(term_catalog().size(), std::size(expected));
  for (std::size_t i = 0; i < std::size(expected); ++i) {
    EXPECT_EQ(term_catalog()[i].name, expected[i]);
    EXPECT_EQ(term_kind_from_name(expected[i]), term_catalog()[i].kind);
  }
  EXPECT_FALSE(term_kind_from_name("nonsense").has_value());
  // The further forms are reported under their effect's name.
  EXPECT_EQ(term_family(TermKind::kPositionRipple), "position_dependent");
  EXPECT_EQ(term_family(TermKind::kPositionBump), "position_dependent");
  EXPECT_EQ(term_family(TermKind::kLoadSaturating), "load_dependent");
  EXPECT_EQ(term_family(TermKind::kViscous), "viscous");
}

TEST(SlidingTerms, FlexibleFormsHaveTheirShapes) {
  Motion m;
  m.x = 0.5;
  m.load = 10.0;
  const Term ripple{TermKind::kPositionRipple, {0.2, 0.1, 3.0}};
  EXPECT_NEAR(term_level(ripple, m, false), 0.2 * std::sin(1.5) + 0.1 * std::cos(1.5), 1e-12);
  const Term bump{TermKind::kPositionBump, {0.3, 0.4, 0.1}};
  EXPECT_NEAR(term_level(bump, m, false), 0.3 * std::exp(-0.5), 1e-12);  // one width away
  const Term sat{TermKind::kLoadSaturating, {0.02, 5.0}};
  EXPECT_NEAR(term_level(sat, m, false), 0.02 * 5.0 * std::tanh(2.0), 1e-12);
  m.load = 1e-3;  // linear for small loads: c_sat x load
  EXPECT_NEAR(term_level(sat, m, false), 0.02 * 1e-3, 1e-9);
}

TEST(SlidingTerms, AddedEffectsContribute) {
  Term viscous{TermKind::kViscous, {0.3}};
  EXPECT_DOUBLE_EQ(term_level(viscous, Motion{.xd = -2.0}, false), 0.6);
  Term load{TermKind::kLoadDependent, {0.01}};
  EXPECT_DOUBLE_EQ(term_level(load, Motion{.load = 50.0}, false), 0.5);
  Term pos{TermKind::kPositionDependent, {0.1, 0.2}};
  EXPECT_DOUBLE_EQ(term_level(pos, Motion{.x = 2.0}, false), 0.1 * 2.0 + 0.2 * 4.0);
  Term time{TermKind::kTimeVarying, {0.01, 0.5, 10.0, 2.0}};
  EXPECT_DOUBLE_EQ(term_level(time, Motion{.t = 5.0}, false), 0.01 * 3.0);
  EXPECT_DOUBLE_EQ(term_level(time, Motion{.t = 10.0}, false), 0.01 * 8.0 + 0.5);
}

TEST(SlidingTerms, DriveIncludesReversalOffset) {
  const TsmFrictionModel model(paper_spec());
  EXPECT_DOUBLE_EQ(model.drive(1.0, -1), 0.8);
  EXPECT_DOUBLE_EQ(model.drive(0.0, +1), 0.2);
  EXPECT_DOUBLE_EQ(model.drive(0.0, 0), 0.0);
}

}  // namespace
}  // namespace tsmh::estimator

namespace tsmh::estimator {
namespace {

// The multiplicative forms scale the sum of the other terms by a factor of
// physical quantities without the friction in them.
TEST(ScalingTerms, LoadScalingMultipliesByTheDistalLoad) {
  TsmModelSpec s = paper_spec();
  s.add(TermKind::kLoadScaling).p = {0.05, 0.02, 0.01};
  TsmFrictionModel model(s);
  const TsmFrictionModel plain(paper_spec());
  Motion m{.xd = 0.5, .xdd = 2.0, .acc_sign = 1.0};
  // At rest the friction is 0: D = drive = 4 N.
  m.drive = 4.0;
  const double g = 1.0 + 0.05 * 4.0 + 0.02 * 4.0 + 0.01 * 0.0 * 4.0;
  EXPECT_NEAR(model.sliding_level(m), plain.sliding_level(m) * g, 1e-12);
  // Unknown drive: factor 1.
  m.drive = std::nan("");
  EXPECT_NEAR(model.sliding_level(m), plain.sliding_level(m), 1e-12);
  // After steps the distal load is drive less the model's own friction, and
  // k_along takes the friction's sign.
  m.drive = 4.0;
  for (int i = 0; i < 200; ++i)
    model.step(m, 1e-3);
  const double f = model.friction();
  ASSERT_GT(f, 1.0);
  const double d = 4.0 - f;
  const double g2 = 1.0 + 0.05 * std::fabs(d) + 0.02 * d + 0.01 * d;
  EXPECT_NEAR(model.sliding_level(m), plain.sliding_level(m) * g2, 1e-12);
}

TEST(ScalingTerms, TensionScalingAndItsBounds) {
  TsmModelSpec s = paper_spec();
  s.add(TermKind::kTensionScaling).p = {0.1, 20.0};
  const TsmFrictionModel model(s);
  const TsmFrictionModel plain(paper_spec());
  Motion m{.xd = -0.5, .xdd = 2.0, .acc_sign = 1.0};
  m.tension = 23.0;
  EXPECT_NEAR(model.sliding_level(m), plain.sliding_level(m) * 1.3, 1e-12);
  m.tension = -1000.0;  // the factor stays >= kMinScaling
  EXPECT_NEAR(model.sliding_level(m), plain.sliding_level(m) * kMinScaling, 1e-12);
  EXPECT_TRUE(std::find(s.fixed.begin(), s.fixed.end(), "tension_scaling.t_ref") != s.fixed.end());
  EXPECT_EQ(term_family(TermKind::kLoadScaling), "load_dependent");
  EXPECT_EQ(term_family(TermKind::kTensionScaling), "tension_dependent");
}

}  // namespace
}  // namespace tsmh::estimator
