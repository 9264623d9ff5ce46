// What no estimator from the encoder can decide. Eq. (4) switches on the sign
// of the acceleration however small it is, so in holds and cruises, where the
// generator's acceleration is exactly zero, a tremor of 1e-12 rad (which no
// encoder sample shows) sets the true friction state. Two worlds with the
// same samples and different truths bound every estimator from below: on one
// of them it is off by at least half the RMSE between the truths.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "estimator/distal_estimator.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

constexpr double kTremor = 1e-12;  // rad, at the default 10 Hz

struct World {
  SyntheticData still, shaken;
};

World worlds(MotionKind kind, std::uint64_t seed) {
  const TsmFrictionModel truth(paper_spec());
  SyntheticConfig config;
  config.motion = kind;
  config.seed = seed;
  config.f_low_hz = 0.2;
  config.f_high_hz = 1.0;
  World w{make_synthetic(truth, config), {}};
  config.tremor_rad = kTremor;
  w.shaken = make_synthetic(truth, config);
  return w;
}

// Half the RMSE between the two truths, % of the first one's peak.
double ambiguity_percent(const World& w) {
  double peak = 0.0, se = 0.0;
  const auto& a = w.still.true_friction;
  const auto& b = w.shaken.true_friction;
  for (std::size_t i = 0; i < a.size(); ++i) {
    peak = std::max(peak, std::fabs(a[i]));
    se += (a[i] - b[i]) * (a[i] - b[i]);
  }
  return 50.0 * std::sqrt(se / static_cast<double>(a.size())) / peak;
}

TEST(SubResolutionTremor, ChangesNoEncoderSample) {
  for (MotionKind kind : {MotionKind::kSurgeon, MotionKind::kCreep, MotionKind::kMultisine}) {
    const World w = worlds(kind, 1);
    ASSERT_EQ(w.still.recording.size(), w.shaken.recording.size());
    EXPECT_EQ(w.still.recording.x_in, w.shaken.recording.x_in) << motion_kind_name(kind);
  }
}

TEST(SubResolutionTremor, LeavesTheFrictionEstimateUnchanged) {
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

TEST(SubResolutionTremor, DecidesTheTruthInHoldsAndCruisesOnly) {
  // Measured: surgeon 2.6-3.9 %, creep 14-17 % on seeds 1-3 (1.8 % and 13 %
  // the least over 100 seeds): above the 1 % target, so no estimator reaches
  // it on both worlds. Without holds (multisine) the tremor's acceleration
  // only outweighs the motion's at isolated zero crossings.
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    EXPECT_GT(ambiguity_percent(worlds(MotionKind::kSurgeon, seed)), 1.5) << seed;
    EXPECT_GT(ambiguity_percent(worlds(MotionKind::kCreep, seed)), 10.0) << seed;
    EXPECT_LT(ambiguity_percent(worlds(MotionKind::kMultisine, seed)), 0.01) << seed;
  }
}

TEST(SubResolutionTremor, RefusesANegativeTremor) {
  const TsmFrictionModel truth(paper_spec());
  SyntheticConfig config;
  config.tremor_rad = -1e-12;
  EXPECT_THROW(make_synthetic(truth, config), std::invalid_argument);
  config.tremor_rad = 1e-12;
  config.tremor_hz = 0.0;
  EXPECT_THROW(make_synthetic(truth, config), std::invalid_argument);
}

}  // namespace
}  // namespace tsmh::estimator
