// The physics world's physics: what must emerge from per-node Coulomb
// friction bounded by mu times tension times bend, checked against theory.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <vector>

#include "estimator/recording.hpp"
#include "physics_world/recorder.hpp"

namespace tsmh::physics_world {
namespace {

constexpr double kDt = 2.5e-5;

TendonParams plain_tendon() {
  TendonParams p;
  p.mu = 0.15;
  p.base_normal_n = 0.0;
  p.drag_n_s_per_m = 0.0;
  p.pretension_n = 20.0;
  return p;
}

std::vector<double> even_wrap(const TendonParams& p, double total) {
  return std::vector<double>(static_cast<std::size_t>(p.segments - 1), total / (p.segments - 1));
}

// Moves the proximal end from u0 at speed v for `seconds`, distal end fixed.
double pull(Tendon& t, double u0, double v, double seconds) {
  const int steps = static_cast<int>(std::round(seconds / kDt));
  double u = u0;
  for (int i = 0; i < steps; ++i) {
    t.set_ends(u, v, 0.0, 0.0);
    t.step(kDt);
    u += v * kDt;
  }
  t.set_ends(u, v, 0.0, 0.0);
  return u;
}

TEST(PhysicsWorldTendon, CapstanRatioWhileSlipping) {
  const TendonParams p = plain_tendon();
  for (double wrap : {1.0, 2.0, 3.0}) {
    Tendon t(p, even_wrap(p, wrap));
    // Pulled at 2 mm/s until slip has spread over the whole sheath.
    double u = pull(t, 0.0, 2e-3, 1.5);
    const double ratio_pull = t.proximal_tension() / t.distal_tension();
    EXPECT_NEAR(ratio_pull, std::exp(p.mu * wrap), 0.01 * std::exp(p.mu * wrap)) << wrap;
    EXPECT_EQ(t.stuck_nodes(), 0) << "every node slides once slip has spread";
    // Released: friction now holds the distal end's tension up.
    pull(t, u, -2e-3, 1.5);
    const double ratio_release = t.proximal_tension() / t.distal_tension();
    EXPECT_NEAR(ratio_release, std::exp(-p.mu * wrap), 0.01 * std::exp(-p.mu * wrap)) << wrap;
  }
}

TEST(PhysicsWorldTendon, SticksBelowBreakawayAndHoldsAtRest) {
  const TendonParams p = plain_tendon();
  Tendon t(p, even_wrap(p, 2.0));
  // 0.05 mm: the proximal tension rises ~2 N, far below what slipping the
  // whole sheath takes (20 (exp(0.3) - 1) = 7 N).
  double u = pull(t, 0.0, 1e-4, 0.5);
  pull(t, u, 0.0, 0.2);
  const double rise = t.proximal_tension() - p.pretension_n;
  EXPECT_GT(rise, 1.0);
  EXPECT_LT(rise, 4.0);
  EXPECT_NEAR(t.distal_tension(), p.pretension_n, 1e-9) << "the distal end must not feel it";
  for (int i = p.segments - 6; i < p.segments; ++i)
    EXPECT_EQ(t.node_position(i), 0.0) << "node " << i << " should still be stuck";
  // Held: static friction keeps the difference, no creep.
  const double held = t.proximal_tension();
  pull(t, u, 0.0, 1.0);
  EXPECT_NEAR(t.proximal_tension(), held, 1e-9);
  // Far past breakaway the distal end follows.
  pull(t, u, 1e-3, 1.0);
  EXPECT_GT(t.distal_tension() - p.pretension_n, 1.0);
}

TEST(PhysicsWorldTendon, DissipatesWhatTheInputDoesOverACycle) {
  TendonParams p = plain_tendon();
  p.drag_n_s_per_m = 0.3;
  p.base_normal_n = 0.02;
  Tendon t(p, even_wrap(p, 2.0));
  // A slow sine of the proximal end (1 mm, 0.5 Hz), distal end fixed; the
  // last of three cycles is in periodic steady state.
  const double amplitude = 1e-3, omega = std::numbers::pi;
  const int per_cycle = static_cast<int>(std::round(2.0 / kDt));
  double work = 0.0, dissipated_before = 0.0, stored_before = 0.0;
  for (int i = 0; i < 3 * per_cycle; ++i) {
    if (i == 2 * per_cycle) {
      dissipated_before = t.dissipated();
      stored_before = t.stored_energy();
    }
    const double time = i * kDt;
    const double u = amplitude * std::sin(omega * time);
    const double v = amplitude * omega * std::cos(omega * time);
    const double d0 = t.dissipated();
    t.set_ends(u, v, 0.0, 0.0);
    const double tension = t.proximal_tension();
    t.step(kDt);
    EXPECT_GE(t.dissipated(), d0) << "friction must never feed energy in";
    if (i >= 2 * per_cycle) work += tension * v * kDt;
  }
  const double dissipated = t.dissipated() - dissipated_before;
  EXPECT_GT(work, 1e-4);
  EXPECT_NEAR(t.stored_energy(), stored_before, 0.02 * work);
  // What the input did went into the sheath (the rest into internal damping).
  EXPECT_NEAR(dissipated, work, 0.05 * work);
}

// A world with the tip free of tissue and objects.
WorldParams free_world(double wrap1, double wrap2) {
  WorldParams w;
  w.tendon1 = plain_tendon();
  w.tendon2 = plain_tendon();
  w.route1 =
      make_route(w.tendon1.segments, {{0.3, 0.08, wrap1 * 0.6}, {0.7, 0.1, wrap1 * 0.4}}, 0.0);
  w.route2 = make_route(w.tendon2.segments, {{0.5, 0.1, wrap2}}, 0.0);
  w.tip.tissue_surface_rad = 100.0;
  w.tip.grasp_surface_rad = -100.0;
  w.tip.external_peak_n_m = 0.0;
  return w;
}

// Sliding friction (N) at +speed and at -speed: mid-stroke of a triangle
// wave of the input, 0.5 rad strokes at `speed` rad/s.
// `tendon1_up`: tendon 1's own friction T1 - T2 at the +speed sample.
std::pair<double, double> sliding_friction(World& world, double speed, double t0 = 0.0,
                                           double* tendon1_up = nullptr) {
  const double stroke = 0.5, half = stroke / speed;
  double up = 0.0, down = 0.0;
  const int steps = static_cast<int>(std::round(2.0 * half / kDt));
  for (int cycle = 0; cycle < 2; ++cycle) {
    for (int i = 0; i < steps; ++i) {
      const double s = i * kDt;
      const bool rising = s < half;
      const double x = rising ? speed * s : stroke - speed * (s - half);
      world.apply_route(t0 + (cycle * steps + i) * kDt);
      world.step(kDt, x, rising ? speed : -speed, 0.0, 0.0);
      const TipState st = world.state();
      const double f = (st.T1 - st.T3) - (st.T2 - st.T4);
      if (std::fabs(s - 0.8 * half) < 0.5 * kDt) {
        up = f;
        if (tendon1_up != nullptr) *tendon1_up = st.T1 - st.T2;
      }
      if (std::fabs(s - 1.8 * half) < 0.5 * kDt) down = f;
    }
  }
  return {up, down};
}

TEST(PhysicsWorld, EqualBendsSlideSymmetricallyUnequalOnesDoNot) {
  World same(free_world(2.0, 2.0));
  const auto [up_same, down_same] = sliding_friction(same, 0.5);
  EXPECT_GT(up_same, 3.0);
  EXPECT_LT(down_same, -3.0);
  EXPECT_NEAR(up_same, -down_same, 0.02 * up_same);
  World unequal(free_world(2.4, 1.2));
  const auto [up, down] = sliding_friction(unequal, 0.5);
  EXPECT_GT(up, 0.0);
  EXPECT_LT(down, 0.0);
  // Tendon 1 (more bent) pulled moving up: more friction that way.
  EXPECT_GT(up / -down, 1.05);
}

TEST(PhysicsWorld, ReroutingChangesTheFriction) {
  WorldParams p = free_world(2.0, 1.5);
  p.reroute.at_s = 4.0;
  p.reroute.ramp_s = 0.5;
  p.reroute.scale1 = 1.5;
  p.reroute.scale2 = 1.5;
  World w(p);
  const auto [up0, down0] = sliding_friction(w, 0.5, 0.0);  // 0-4 s: as routed
  const auto [up1, down1] = sliding_friction(w, 0.5, 4.0);  // 4-8 s: bent 1.5x more
  EXPECT_GT(up1 / up0, 1.3);
  EXPECT_LT(up1 / up0, 1.9);
  EXPECT_GT(down1 / down0, 1.3);
}

TEST(PhysicsWorld, FrictionGrowsWithTheLoadTheTendonsCarry) {
  // The same sliding with the tip pushed against tissue: the pulled
  // tendon's tension and with it its friction grow (capstan), by the
  // tension it carries: T1 - T2 = T2 (exp(mu wrap) - 1).
  WorldParams p = free_world(2.0, 1.5);
  World free(p);
  double free1 = 0.0, loaded1 = 0.0;
  sliding_friction(free, 0.5, 0.0, &free1);
  p.tip.tissue_surface_rad = 0.1;
  p.tip.tissue_stiffness = 1.0;
  p.tip.tissue_stiffening = 0.0;
  World loaded(p);
  sliding_friction(loaded, 0.5, 0.0, &loaded1);
  EXPECT_GT(loaded1, 1.3 * free1);
}

TEST(PhysicsWorldRecording, SensorsTruthAndFormat) {
  RunConfig run;
  run.kind = MotionKind::kPalpation;
  run.motion_seed = 3;
  run.duration_s = 6.0;
  const WorldRecording r = record(random_world(2), run);
  const auto& rec = r.recording;
  ASSERT_EQ(rec.size(), 6001u);
  const double q = 2.0 * std::numbers::pi / 40960.0;
  double noise = 0.0, peak_contact = 0.0;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    EXPECT_NEAR(rec.x_in[i] / q, std::round(rec.x_in[i] / q), 1e-6);
    EXPECT_NEAR(r.friction_true[i] * rec.radius_m, r.tau_in_true[i] - r.tau_out_true[i], 1e-15);
    const double e = rec.tau_in[i] - r.tau_in_true[i];
    noise += e * e;
    peak_contact = std::max(peak_contact, r.contact[i]);
  }
  // tau_in = R (T1 - T3), each with 0.3 N of noise.
  EXPECT_NEAR(std::sqrt(noise / rec.size()), 0.01 * 0.3 * std::sqrt(2.0), 0.0005);
  EXPECT_EQ(peak_contact, 1.0) << "palpation must touch the tissue";
  // The CSV reads back through the recording contract, truth columns beside.
  const auto path = std::filesystem::temp_directory_path() / "tsmh_physics_world_test.csv";
  write_csv(r, path);
  const estimator::Recording back = estimator::read_recording_csv(path);
  EXPECT_EQ(back.size(), rec.size());
  EXPECT_DOUBLE_EQ(back.radius_m, 0.01);
  EXPECT_FALSE(back.T1.empty());
  std::filesystem::remove(path);
  // Deterministic per seed; another world seed is another sheath.
  const WorldRecording again = record(random_world(2), run);
  EXPECT_EQ(again.recording.tau_in, rec.tau_in);
  const WorldRecording other = record(random_world(4), run);
  EXPECT_NE(other.friction_true, r.friction_true);
}

}  // namespace
}  // namespace tsmh::physics_world
