// Offline zero-phase derivatives: accuracy on a quantised sine,
// uneven intervals, no lag, refusals, and what they mean for the friction
// model: the true parameters on smoothed derivatives vs the true friction.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "estimator/offline_derivatives.hpp"
#include "estimator/simulate.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

constexpr double kQuantum = 2.0 * std::numbers::pi / 40960.0;

TEST(OfflineDerivatives, QuantisedSineWithUnevenIntervalsAndNoLag) {
  const double a = 0.8, w = 2.0 * std::numbers::pi * 0.5;
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> jitter(0.5e-3, 1.5e-3);
  std::vector<double> t, x;
  for (double tt = 0.0; tt < 20.0; tt += jitter(rng)) {
    t.push_back(tt);
    x.push_back(std::round(a * std::sin(w * tt) / kQuantum) * kQuantum);
  }
  const auto d = smooth_derivatives(t, x);
  double ev = 0.0, ea = 0.0, lead = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < 1.0 || t[i] > 19.0) continue;  // the ends see one side only
    const double v = a * w * std::cos(w * t[i]), acc = -a * w * w * std::sin(w * t[i]);
    ev += (d.xd[i] - v) * (d.xd[i] - v);
    ea += (d.xdd[i] - acc) * (d.xdd[i] - acc);
    lead += (d.xd[i] - v) * acc;  // a lag correlates the error with -xdd
    ++n;
  }
  const double rms_v = std::sqrt(ev / n), rms_a = std::sqrt(ea / n);
  RecordProperty("velocity_rms_error", std::to_string(rms_v));
  RecordProperty("acceleration_rms_error", std::to_string(rms_a));
  EXPECT_LT(rms_v, 0.003);  // peak velocity 2.5 rad/s; the online filter: 0.006
  EXPECT_LT(rms_a, 0.1);    // peak acceleration 7.9 rad/s^2
  // Zero phase: the equivalent delay (error along xdd / mean xdd^2) under 0.2 ms.
  double a2 = 0.0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < 1.0 || t[i] > 19.0) continue;
    const double acc = -a * w * w * std::sin(w * t[i]);
    a2 += acc * acc;
  }
  EXPECT_LT(std::fabs(lead / a2), 2e-4);
}

TEST(OfflineDerivatives, RefusesMismatchedOrTooShortInput) {
  const std::vector<double> t = {0.0, 0.001, 0.002}, x = {0.0, 0.1};
  EXPECT_THROW(smooth_derivatives(t, x), std::invalid_argument);
  EXPECT_THROW(smooth_derivatives(std::vector<double>{0.0, 1.0}, std::vector<double>{0.0, 1.0}),
               std::invalid_argument);
}

// The limit any fit on these derivatives can reach: the true parameters
// simulated on them, against the true friction (the fit's target is
// 1 % of peak; the online differentiator's floor is about 4 %).
TEST(OfflineDerivatives, TrueParametersReachTheTrueFrictionWithinOnePercent) {
  SyntheticConfig c;
  c.seed = 77;
  c.duration_s = 20.0;
  const TsmFrictionModel truth(paper_spec());
  const auto syn = make_synthetic(truth, c);
  auto m = truth.clone();
  const auto f = simulate_friction(*m, offline_motion(syn.recording));
  double e2 = 0.0, peak = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    peak = std::max(peak, std::fabs(syn.true_friction[i]));
    if (syn.recording.t[i] < 0.5) continue;
    e2 += (f[i] - syn.true_friction[i]) * (f[i] - syn.true_friction[i]);
    ++n;
  }
  const double pct = 100.0 * std::sqrt(e2 / n) / peak;
  RecordProperty("true_params_pct_of_peak", std::to_string(pct));
  EXPECT_LT(pct, 1.0);  // 0.51 % here; 0.18-0.76 % over seeds 1-10 (docs/identification.md)
}

}  // namespace
}  // namespace tsmh::estimator
