#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "estimator/baselines.hpp"
#include "estimator/simulate.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

std::vector<Motion> sine(double amplitude, double hz, double seconds, double load = 0.0) {
  std::vector<Motion> m;
  const double w = 2.0 * std::numbers::pi * hz;
  for (int i = 0; i * 1e-3 <= seconds; ++i) {
    const double t = i * 1e-3;
    const double xdd = -amplitude * w * w * std::sin(w * t);
    m.push_back(
        {t, amplitude * std::sin(w * t), amplitude * w * std::cos(w * t), xdd, sign_of(xdd), load});
  }
  return m;
}

TEST(Baselines, DahlPresetOfTheComposableModelIsDahl) {
  // n = 1, sigma = 1, one Coulomb level: eq. (4) becomes Dahl's model with
  // sigma0 = gamma theta and Fc = gamma rho1 (docs/friction-model.md).
  const TsmModelSpec spec = dahl_spec();
  TsmFrictionModel composable(spec);
  DahlModel dahl({spec.gamma * spec.theta, spec.gamma * spec.terms[0].p[0]});
  const auto motion = sine(0.8, 0.5, 6.0);
  const auto a = simulate_friction(composable, motion);
  const auto b = simulate_friction(dahl, motion);
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    worst = std::max(worst, std::fabs(a[i] - b[i]));
  // Both integrate the same ODE; they differ only in the held velocity
  // (trapezoid vs end point) over each 1 ms interval: under 1 % of Fc.
  EXPECT_LT(worst, 0.09);

  // At constant velocity the two discretisations coincide: exact agreement.
  std::vector<Motion> ramp;
  for (int i = 0; i < 500; ++i)
    ramp.push_back({i * 1e-3, 0.7 * i * 1e-3, 0.7, 0.0, 0, 0.0});
  const auto ra = simulate_friction(composable, ramp);
  const auto rb = simulate_friction(dahl, ramp);
  for (std::size_t i = 0; i < ra.size(); ++i)
    EXPECT_NEAR(ra[i], rb[i], 1e-6) << i;
}

TEST(Baselines, DahlSaturatesAtCoulombLevel) {
  DahlModel dahl({150.0, 9.0});
  const auto f = simulate_friction(dahl, sine(0.8, 0.5, 4.0));
  EXPECT_NEAR(*std::max_element(f.begin() + 2000, f.end()), 9.0, 0.01);
  EXPECT_NEAR(*std::min_element(f.begin() + 2000, f.end()), -9.0, 0.01);
}

TEST(Baselines, LuGreShowsStribeckAndViscous) {
  LuGreModel lugre({300.0, 0.0, 0.5, 8.0, 12.0, 0.1});
  std::vector<Motion> slow, fast;
  for (int i = 0; i < 20000; ++i) {
    slow.push_back({i * 1e-3, 0.0, 0.05, 0.0, 0, 0.0});
    fast.push_back({i * 1e-3, 0.0, 2.0, 0.0, 0, 0.0});
  }
  const double f_slow = simulate_friction(lugre, slow).back();
  const double f_fast = simulate_friction(lugre, fast).back();
  EXPECT_NEAR(f_slow, 8.0 + 4.0 * std::exp(-0.25) + 0.5 * 0.05, 0.01);  // near Fs at low speed
  EXPECT_NEAR(f_fast, 8.0 + 0.5 * 2.0, 0.01);                           // Fc + sigma2 v
}

TEST(Baselines, CoulombCapstanGrowsWithLoadAndJumpsAtReversal) {
  CoulombCapstanModel kaneko({5.0, 0.2, 0.01});
  EXPECT_NEAR(kaneko.step({0.0, 0.0, 1.0, 0.0, 0, 0.0}, 1e-3), 5.0, 1e-9);
  EXPECT_NEAR(kaneko.step({0.0, 0.0, 1.0, 0.0, 0, 50.0}, 1e-3), 15.0, 1e-9);
  EXPECT_NEAR(kaneko.step({0.0, 0.0, -1.0, 0.0, 0, 50.0}, 1e-3), -15.0, 1e-9);
  EXPECT_NEAR(kaneko.step({0.0, 0.0, 0.0, 0.0, 0, 50.0}, 1e-3), 0.0, 1e-9);  // no force at rest
}

TEST(Baselines, BadParametersAreRefusedNamingTheField) {
  try {
    LuGreModel({300.0, 0.0, 0.5, 8.0, 12.0, -1.0});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("params.vs"), std::string::npos);
  }
  EXPECT_THROW(DahlModel({0.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(CoulombCapstanModel({1.0, 1.5, 0.01}), std::invalid_argument);
}

// Each value's rule and its words, at and beside the boundary: the message
// names the value and what it must be; NaN is refused everywhere.
template <class Model>
void expect_refused(typename Model::Params p, const std::string& message) {
  try {
    Model m(p);
    ADD_FAILURE() << "accepted; expected " << message;
  } catch (const std::invalid_argument& e) {
    EXPECT_EQ(std::string(e.what()), message);
  }
}

TEST(Baselines, EachValueIsCheckedByItsOwnRule) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  expect_refused<DahlModel>({0.0, 9.2}, "params.sigma0: must be > 0");
  expect_refused<DahlModel>({148.4, nan}, "params.fc: must be > 0");
  expect_refused<LuGreModel>({148.4, -0.1, 0.0, 9.2, 15.0, 0.2}, "params.sigma1: must be >= 0");
  expect_refused<LuGreModel>({148.4, 1.0, -1e-9, 9.2, 15.0, 0.2}, "params.sigma2: must be >= 0");
  expect_refused<LuGreModel>({148.4, 1.0, 0.0, 9.2, 0.0, 0.2}, "params.fs: must be > 0");
  expect_refused<CoulombCapstanModel>({-1.0, 0.3, 0.02}, "params.f0: must be >= 0");
  expect_refused<CoulombCapstanModel>({9.2, 1.0, 0.02}, "params.capstan: must be in [0, 1)");
  expect_refused<CoulombCapstanModel>({9.2, -0.1, 0.02}, "params.capstan: must be in [0, 1)");
  expect_refused<CoulombCapstanModel>({9.2, 0.3, 0.0}, "params.v_eps: must be > 0");
  // The first bad value is the one named.
  expect_refused<LuGreModel>({-1.0, -1.0, 0.0, 9.2, 15.0, 0.2}, "params.sigma0: must be > 0");
  // On the boundary of >= 0 and [0, 1): accepted.
  EXPECT_NO_THROW(LuGreModel({148.4, 0.0, 0.0, 9.2, 15.0, 0.2}));
  EXPECT_NO_THROW(CoulombCapstanModel({0.0, 0.0, 0.02}));
  EXPECT_NO_THROW(CoulombCapstanModel({0.0, 0.999, 0.02}));
  // parameters(): name, fit bounds and unit per value, in Params' order.
  const auto lugre = LuGreModel().parameters();
  ASSERT_EQ(lugre.size(), 6U);
  EXPECT_EQ(lugre[1].name, "params.sigma1");
  EXPECT_DOUBLE_EQ(lugre[1].value, 1.0);
  EXPECT_DOUBLE_EQ(lugre[1].upper, 100.0);
  EXPECT_EQ(lugre[1].unit, "N s/rad");
  EXPECT_EQ(lugre[5].name, "params.vs");
  EXPECT_DOUBLE_EQ(lugre[5].lower, 1e-3);
  const auto capstan = CoulombCapstanModel().parameters();
  ASSERT_EQ(capstan.size(), 3U);
  EXPECT_EQ(capstan[1].name, "params.capstan");
  EXPECT_DOUBLE_EQ(capstan[1].upper, 0.99);
  EXPECT_EQ(capstan[1].unit, "");
  EXPECT_FALSE(capstan[2].fixed);
}

// Every baseline: set_values takes one value per parameter, in parameters()'
// order, and keeps its kind; a wrong count or a bad value is refused.
template <class Model>
void expect_set_values_round_trip(const char* kind) {
  Model model;
  EXPECT_EQ(model.kind(), kind);
  std::vector<double> v;
  for (const auto& p : model.parameters())
    v.push_back(p.value * 1.1);
  model.set_values(v);
  const auto after = model.parameters();
  ASSERT_EQ(after.size(), v.size()) << kind;
  for (std::size_t i = 0; i < v.size(); ++i)
    EXPECT_DOUBLE_EQ(after[i].value, v[i]) << kind << " " << after[i].name;
  EXPECT_EQ(model.kind(), kind);
  v.push_back(1.0);
  try {
    model.set_values(v);
    ADD_FAILURE() << kind << ": one value too many accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(kind), std::string::npos) << e.what();
  }
  v.assign(after.size(), -1.0);
  EXPECT_THROW(model.set_values(v), std::invalid_argument) << kind;
  EXPECT_DOUBLE_EQ(model.parameters()[0].value, after[0].value) << kind << ": changed by a refusal";
}

TEST(Baselines, SetValuesRoundTripsParameters) {
  expect_set_values_round_trip<DahlModel>("dahl");
  expect_set_values_round_trip<LuGreModel>("lugre");
  expect_set_values_round_trip<CoulombCapstanModel>("coulomb_capstan");
}

}  // namespace
}  // namespace tsmh::estimator
