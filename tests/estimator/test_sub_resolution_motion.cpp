// What no estimator from the encoder can decide. Eq. (4) switches on the sign
// of the acceleration however small it is, so in holds and cruises, where the
// generator's acceleration is exactly zero, a tremor of 1e-12 rad or a
// constant acceleration of +-1e-16 rad/s^2 (which no encoder sample shows)
// sets the true friction state. Two worlds with the same samples and
// different truths bound every estimator from below: on one of them it is
// off by at least half the RMSE between the truths.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <vector>

#include "estimator/distal_estimator.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

constexpr double kTremor = 1e-12;  // rad, at the default 10 Hz
constexpr double kDrift = 1e-16;   // rad/s^2

struct World {
  SyntheticData still, shaken, faster, slower;
};

World worlds(MotionKind kind, std::uint64_t seed) {
  const TsmFrictionModel truth(paper_spec());
  SyntheticConfig config;
  config.motion = kind;
  config.seed = seed;
  config.f_low_hz = 0.2;
  config.f_high_hz = 1.0;
  World w{make_synthetic(truth, config), {}, {}, {}};
  config.tremor_rad = kTremor;
  w.shaken = make_synthetic(truth, config);
  config.tremor_rad = 0.0;
  config.drift_acc = kDrift;
  w.faster = make_synthetic(truth, config);
  config.drift_acc = -kDrift;
  w.slower = make_synthetic(truth, config);
  return w;
}

// Half the RMSE between two truths, % of the generator's peak.
double ambiguity_percent(const World& w, const SyntheticData& a, const SyntheticData& b) {
  double peak = 0.0, se = 0.0;
  for (std::size_t i = 0; i < a.true_friction.size(); ++i) {
    peak = std::max(peak, std::fabs(w.still.true_friction[i]));
    const double d = a.true_friction[i] - b.true_friction[i];
    se += d * d;
  }
  return 50.0 * std::sqrt(se / static_cast<double>(a.true_friction.size())) / peak;
}
double tremor_ambiguity(const World& w) {
  return ambiguity_percent(w, w.still, w.shaken);
}
double drift_ambiguity(const World& w) {
  return ambiguity_percent(w, w.faster, w.slower);
}

TEST(SubResolutionMotion, ChangesNoEncoderSample) {
  for (MotionKind kind :
       {MotionKind::kSurgeon, MotionKind::kCreep, MotionKind::kReversals, MotionKind::kMultisine}) {
    const World w = worlds(kind, 1);
    for (const SyntheticData* other : {&w.shaken, &w.faster, &w.slower}) {
      ASSERT_EQ(w.still.recording.size(), other->recording.size());
      EXPECT_EQ(w.still.recording.x_in, other->recording.x_in) << motion_kind_name(kind);
    }
  }
}

TEST(SubResolutionMotion, LeavesTheFrictionEstimateUnchanged) {
  // The paper's model has no load term: after the start, the friction
  // estimate depends on the encoder alone, although the proximal torque
  // carries the other truth. (The server's default start tares the state
  // from the proximal torque once; the accuracy suite starts at zero.)
  const World w = worlds(MotionKind::kSurgeon, 2);
  DistalTorqueEstimator a(std::make_unique<TsmFrictionModel>(paper_spec()), 0.01,
                          DifferentiatorConfig{}, StartState::kZero);
  DistalTorqueEstimator b(std::make_unique<TsmFrictionModel>(paper_spec()), 0.01,
                          DifferentiatorConfig{}, StartState::kZero);
  const Recording& ra = w.still.recording;
  const Recording& rb = w.shaken.recording;
  bool torque_differs = false;
  for (std::size_t i = 0; i < ra.size(); ++i) {
    const Estimate ea = a.update(ra.t[i], ra.x_in[i], ra.tau_in[i]);
    const Estimate eb = b.update(rb.t[i], rb.x_in[i], rb.tau_in[i]);
    ASSERT_EQ(ea.friction, eb.friction) << "sample " << i;
    torque_differs = torque_differs || ra.tau_in[i] != rb.tau_in[i];
  }
  EXPECT_TRUE(torque_differs);
}

TEST(SubResolutionMotion, DecidesTheTruthInHoldsAndCruisesOnly) {
  // Measured by online_accuracy on seeds 1-3 (tremor / drift): surgeon 2.6-3.9 / 59-62 %, creep
  // 14-17 / 67-77 %, reversals 0.6-0.9 / 4.3-7.7 %: with the drift above the
  // 1 % target on all three, so no estimator reaches it on both worlds of a
  // pair. Without holds or cruises (multisine) the perturbations' sign only
  // outweighs the motion's at isolated zero crossings of the acceleration.
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const World surgeon = worlds(MotionKind::kSurgeon, seed);
    EXPECT_GT(tremor_ambiguity(surgeon), 1.5) << seed;
    EXPECT_GT(drift_ambiguity(surgeon), 30.0) << seed;
    const World creep = worlds(MotionKind::kCreep, seed);
    EXPECT_GT(tremor_ambiguity(creep), 10.0) << seed;
    EXPECT_GT(drift_ambiguity(creep), 30.0) << seed;
    EXPECT_GT(drift_ambiguity(worlds(MotionKind::kReversals, seed)), 2.0) << seed;
    const World multisine = worlds(MotionKind::kMultisine, seed);
    EXPECT_LT(tremor_ambiguity(multisine), 0.01) << seed;
    EXPECT_LT(drift_ambiguity(multisine), 0.01) << seed;
  }
}

TEST(SubResolutionMotion, RefusesAnUnusablePerturbation) {
  const TsmFrictionModel truth(paper_spec());
  SyntheticConfig config;
  config.tremor_rad = -1e-12;
  EXPECT_THROW(make_synthetic(truth, config), std::invalid_argument);
  config.tremor_rad = 1e-12;
  config.tremor_hz = 0.0;
  EXPECT_THROW(make_synthetic(truth, config), std::invalid_argument);
  config.tremor_hz = 10.0;
  config.drift_acc = std::nan("");
  EXPECT_THROW(make_synthetic(truth, config), std::invalid_argument);
}

}  // namespace
}  // namespace tsmh::estimator
