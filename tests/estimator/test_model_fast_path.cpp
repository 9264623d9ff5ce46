// The model step's fast paths (the inline RK4 step of the paper's shape, the
// flat evaluation of the paper's sliding terms) against the general code
// they shortcut: equal bit for bit, sign of zero included, over random
// inputs that mostly take the fast path and partly do not.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <vector>

#include "estimator/bouc_wen_state.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

std::uint64_t bits(double v) {
  return std::bit_cast<std::uint64_t>(v);
}

TEST(ModelFastPath, BoucWenStepEqualsGeneralPathBitForBit) {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  const std::vector<BoucWenShape> shapes = {
      {15.5181, 2.0, 1.0}, {3.0, 2.0, 1.0}, {80.0, 2.0, 1.0}, {12.6, 2.0, 1.97}, {15.5, 1.0, 1.0}};
  int fast_cases = 0, other_cases = 0;
  for (int i = 0; i < 400000; ++i) {
    const BoucWenShape& s = shapes[static_cast<std::size_t>(i) % shapes.size()];
    const double ff = 1e-3 + 3.0 * uni(rng);
    // u0 within +-3: inside the fast path's |u0| <= 2 and beyond it.
    const double z = (6.0 * uni(rng) - 3.0) * ff * (i % 97 == 0 ? 0.0 : 1.0);
    const double g = i % 89 == 0 ? 0.0 : 8.0 * uni(rng) - 4.0;
    // Mostly 1 kHz, sometimes jittered or a dropped-sample gap.
    const double dt = i % 7 == 0 ? 0.03 * uni(rng) : (i % 3 == 0 ? 1e-3 : 2e-3 * uni(rng));
    const double fast = advance_bouc_wen_state(z, ff, g, dt, s);
    const double general = advance_bouc_wen_state_general(z, ff, g, dt, s);
    ASSERT_EQ(bits(fast), bits(general)) << "z " << z << " ff " << ff << " g " << g << " dt " << dt
                                         << " shape " << s.theta << ' ' << s.n << ' ' << s.sigma;
    const double u0 = z / ff, travel = s.theta * std::fabs(g) * dt / ff;
    const bool fast_case = s.n == 2.0 && s.sigma == 1.0 && g != 0.0 && std::fabs(u0) <= 2.0 &&
                           travel > 0.0 && travel <= kMaxRk4Travel;
    (fast_case ? fast_cases : other_cases)++;
  }
  // Both sides of the fast path's conditions were exercised.
  EXPECT_GT(fast_cases, 100000);
  EXPECT_GT(other_cases, 100000);
}

// Every subset of the paper's terms in catalog order takes the flat
// evaluation; each is checked against the plain sum of the terms.
TEST(ModelFastPath, FlatSlidingLevelEqualsSumOfTermsBitForBit) {
  const TermKind paper_kinds[] = {TermKind::kCoulomb, TermKind::kDirectionAsymmetry,
                                  TermKind::kStribeck, TermKind::kAccelerationDependence,
                                  TermKind::kReversalOffset};
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> uni(0.0, 1.0);
  for (unsigned subset = 1; subset < 32; ++subset) {
    TsmModelSpec spec = paper_spec();
    spec.terms.clear();
    for (unsigned k = 0; k < 5; ++k) {
      if (subset & (1u << k)) spec.add(paper_kinds[k]);
    }
    for (int draw = 0; draw < 20; ++draw) {
      // Parameters across their identification bounds (zeros included).
      for (auto& t : spec.terms) {
        const auto& params = term_info(t.kind).params;
        for (std::size_t k = 0; k < params.size(); ++k) {
          const double r = uni(rng);
          t.p[k] =
              r < 0.1 ? params[k].lower : params[k].lower + r * (params[k].upper - params[k].lower);
        }
      }
      const TsmFrictionModel model(spec);
      ASSERT_TRUE(model.uses_flat_level()) << subset;
      const bool asymmetric = spec.has(TermKind::kDirectionAsymmetry);
      for (int i = 0; i < 2000; ++i) {
        const double xd = i % 50 == 0 ? (i % 100 == 0 ? 0.0 : -0.0) : 10.0 * uni(rng) - 5.0;
        const double xdd = i % 30 == 0 ? 0.0 : 200.0 * uni(rng) - 100.0;
        const double acc_sign = i % 4 == 0 ? 2.0 * uni(rng) - 1.0 : sign_of(xdd);
        const Motion m{i * 1e-3, uni(rng), xd, xdd, acc_sign, 20.0 * uni(rng)};
        const double general =
            std::max(sum_of_term_levels(spec.terms, m, asymmetric), kMinSlidingLevel);
        ASSERT_EQ(bits(model.sliding_level(m)), bits(general))
            << "subset " << subset << " xd " << xd << " xdd " << xdd;
      }
    }
  }
}

TEST(ModelFastPath, OtherTermsOrOrderTakeTheGeneralSum) {
  TsmModelSpec with_viscous = paper_spec();
  with_viscous.add(TermKind::kViscous).p[0] = 0.3;
  EXPECT_FALSE(TsmFrictionModel(with_viscous).uses_flat_level());
  TsmModelSpec reordered = paper_spec();
  std::swap(reordered.terms[0], reordered.terms[2]);  // stribeck before coulomb
  EXPECT_FALSE(TsmFrictionModel(reordered).uses_flat_level());
  EXPECT_TRUE(TsmFrictionModel(paper_spec()).uses_flat_level());
  EXPECT_TRUE(TsmFrictionModel(dahl_spec()).uses_flat_level());
}

// The whole step (trapezoidal drive, floored Ff, state update) against the
// same step written with the general functions, over motion that reverses,
// speeds up and drops samples.
TEST(ModelFastPath, ModelStepEqualsGeneralComputationBitForBit) {
  for (const TsmModelSpec& spec : {paper_spec(), dahl_spec()}) {
    TsmFrictionModel model(spec);
    const BoucWenShape shape{spec.theta, spec.n, spec.sigma};
    const bool asymmetric = spec.has(TermKind::kDirectionAsymmetry);
    double lambda = 0.0;
    for (const auto& t : spec.terms) {
      if (t.kind == TermKind::kReversalOffset) lambda = t.p[0];
    }
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> jitter(0.5e-3, 1.5e-3);
    double z = 0.0, xd_prev = 0.0, t = 0.0;
    for (int i = 0; i < 100000; ++i) {
      const double dt = i % 500 == 0 ? 0.03 : jitter(rng);
      t += dt;
      const double w = 2.0 * std::numbers::pi * (0.3 + 0.2 * std::sin(0.05 * t));
      const double xd = 1.5 * std::cos(w * t) + 0.4 * std::cos(5.3 * t);
      const double xdd = -1.5 * w * std::sin(w * t) - 2.12 * std::sin(5.3 * t);
      const Motion m{t, 1.5 / w * std::sin(w * t), xd, xdd, sign_of(xdd), 5.0};
      const double f = model.step(m, dt);

      const double xd_mid = i > 0 ? 0.5 * (xd_prev + m.xd) : m.xd;
      xd_prev = m.xd;
      const double ff = std::max(sum_of_term_levels(spec.terms, m, asymmetric), kMinSlidingLevel);
      z = advance_bouc_wen_state_general(z, ff, xd_mid + lambda * m.acc_sign, dt, shape);
      ASSERT_EQ(bits(f), bits(spec.gamma * z)) << "sample " << i;
    }
  }
}

}  // namespace
}  // namespace tsmh::estimator
