// The tendon chain alone: capstan law, exact stick, dissipation.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "virtual_tissue_slave/tendon_chain.hpp"

namespace vts = tsmh::virtual_tissue_slave;

namespace {

vts::TendonParams params(double mu, double wrap) {
  vts::TendonParams p;
  p.mu = mu;
  p.wrap_rad = wrap;
  p.pretension_n = 20.0;
  p.stiffness_ea_n = 4300.0;
  p.segments = 16;
  return p;
}

// Pulls the proximal end in small steps with the distal end fixed, until the
// slip zone has reached the distal end.
void pull(vts::TendonChain& chain, double to_m, int steps = 400) {
  const double from = chain.node_position(0);
  for (int k = 1; k <= steps; ++k)
    chain.solve(from + (to_m - from) * k / steps, 0.0, 1e-4);
}

}  // namespace

TEST(TendonChain, StartsAtPretensionEverywhere) {
  vts::TendonChain chain(params(0.1, 3.0));
  for (int j = 1; j <= chain.segments(); ++j)
    EXPECT_DOUBLE_EQ(chain.tension(j), 20.0);
  EXPECT_DOUBLE_EQ(chain.friction_force(), 0.0);
}

TEST(TendonChain, SlidingTensionRatioFollowsTheCapstanLaw) {
  for (double wrap : {1.0, 3.0, 6.0}) {
    for (double mu : {0.05, 0.1, 0.2}) {
      vts::TendonChain chain(params(mu, wrap));
      pull(chain, 0.01);  // 10 mm: far past the whole tendon slipping
      for (int i = 1; i < chain.segments(); ++i)
        ASSERT_EQ(chain.node_regime(i), 1) << "node " << i << " should slide";
      const double ratio = chain.proximal_tension() / chain.distal_tension();
      EXPECT_NEAR(ratio, std::exp(mu * wrap), 0.01 * std::exp(mu * wrap))
          << "mu " << mu << " wrap " << wrap;
    }
  }
}

TEST(TendonChain, SmallReversalSticksAndLeavesTheDistalTensionUntouched) {
  vts::TendonChain chain(params(0.1, 3.0));
  pull(chain, 0.01);
  const double distal = chain.distal_tension();
  const double proximal = chain.proximal_tension();
  // Back by 0.05 mm: only the first segment relaxes, everything else sticks.
  chain.solve(0.01 - 5e-5, 0.0, 1e-4);
  EXPECT_LT(chain.proximal_tension(), proximal - 1.0);
  EXPECT_DOUBLE_EQ(chain.distal_tension(), distal);
  int stuck = 0;
  for (int i = 1; i < chain.segments(); ++i)
    stuck += chain.node_regime(i) == 0 ? 1 : 0;
  EXPECT_GE(stuck, chain.segments() - 2);
}

TEST(TendonChain, WithoutFrictionTensionIsUniform) {
  vts::TendonChain chain(params(0.0, 3.0));
  chain.solve(0.002, -0.001, 1e-4);
  const double expected = 20.0 + 4300.0 * 0.003 / 1.5;
  for (int j = 1; j <= chain.segments(); ++j)
    EXPECT_NEAR(chain.tension(j), expected, 1e-9);
}

TEST(TendonChain, FrictionNeverCreatesEnergy) {
  // Random walks of both ends, with and without drag and capstan: the work
  // the segments do on the (massless) sheath nodes is never negative.
  std::mt19937_64 rng(7);
  std::normal_distribution<double> step(0.0, 2e-5);
  for (int variant = 0; variant < 3; ++variant) {
    vts::TendonChain chain(params(0.15, 4.0));
    vts::ChainFriction f;
    f.viscous_n_s_per_m = variant == 1 ? 50.0 : 0.0;
    f.capstan = variant != 2;
    chain.set_friction(f);
    double s0 = 0.0, sn = 0.0, total = 0.0;
    for (int k = 0; k < 20000; ++k) {
      s0 += step(rng);
      sn += 0.3 * step(rng);
      const auto info = chain.solve(s0, sn, 1e-4);
      ASSERT_GE(info.dissipated_j, -1e-12) << "variant " << variant << " step " << k;
      ASSERT_FALSE(info.used_fallback);
      total += info.dissipated_j;
    }
    EXPECT_GT(total, 0.0);
  }
}

TEST(TendonChain, ClosedCycleOfTheEndsDissipates) {
  // Energy balance over a quasi-static cycle of the proximal end (distal end
  // fixed): the work put in equals the dissipation (the shape returns), and
  // it is positive: the loop runs the right way round.
  vts::TendonChain chain(params(0.1, 3.0));
  double work = 0.0, dissipated = 0.0;
  double prev = 0.0;
  for (int cycle = 0; cycle < 3; ++cycle) {
    for (int k = 1; k <= 2000; ++k) {
      const double s = 0.004 * std::sin(2.0 * M_PI * k / 2000.0);
      const double t_before = chain.proximal_tension();
      const auto info = chain.solve(s, 0.0, 1e-4);
      work += 0.5 * (t_before + chain.proximal_tension()) * (s - prev);  // trapezoid
      dissipated += info.dissipated_j;
      prev = s;
    }
  }
  EXPECT_GT(dissipated, 0.0);
  EXPECT_NEAR(work - chain.elastic_energy(), dissipated, 0.02 * dissipated);
}

TEST(TendonChain, SlackSegmentsCarryNoTension) {
  auto p = params(0.1, 3.0);
  p.pretension_n = 2.0;
  vts::TendonChain chain(p);
  chain.solve(-0.01, 0.0, 1e-4);  // push 10 mm in: compressive stretch beyond the pretension
  for (int j = 1; j <= chain.segments(); ++j)
    EXPECT_GE(chain.tension(j), 0.0);
  EXPECT_EQ(chain.proximal_tension(), 0.0);
}

TEST(TendonChain, RejectsBadParameters) {
  auto p = params(0.1, 3.0);
  p.segments = 1;
  EXPECT_THROW(vts::TendonChain{p}, std::invalid_argument);
  p = params(-0.1, 3.0);
  EXPECT_THROW(vts::TendonChain{p}, std::invalid_argument);
  vts::TendonChain chain(params(0.1, 3.0));
  try {
    chain.set_wrap(-1.0);
    FAIL() << "negative wrap accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("wrap_rad"), std::string::npos) << e.what();
  }
}
