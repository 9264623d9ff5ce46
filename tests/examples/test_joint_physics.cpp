// One joint: what must emerge from the tendon physics (capstan under load,
// dead zone at reversal, hysteresis asymmetry, load-dependent friction) and
// that friction never creates energy.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "plant_drive.hpp"
#include "virtual_tissue_slave/joint_plant.hpp"
#include "virtual_tissue_slave/slave.hpp"

namespace vts = tsmh::virtual_tissue_slave;
using vts::testing::drive;

namespace {

vts::JointParams joint1() {
  return vts::paper_slave().joints[0];
}

vts::TissueParams hard_at(double surface) {
  auto t = vts::tissue_preset("hard");
  t.surface_rad = surface;
  return t;
}

// Input travel after a reversal at the top of a slow triangle wave before the
// output has moved 1 mrad back: the dead zone (backlash) of the transmission.
double dead_zone(vts::JointParams p) {
  vts::JointPlant plant(p);
  const double amp = 0.6, speed = 0.4;  // rad, rad/s
  // Up to +amp, then down again.
  drive(
      plant, [&](double t) { return std::min(speed * t, amp); }, amp / speed + 0.5);
  const double out_at_top = plant.truth().x_out;
  const double in_at_top = plant.truth().x_in;
  double travel = -1.0;
  drive(
      plant, [&](double t) { return amp - speed * t; }, 2.0 * amp / speed,
      [&](double) {
        if (travel < 0 && out_at_top - plant.truth().x_out > 1e-3)
          travel = in_at_top - plant.truth().x_in;
      });
  return travel;
}

}  // namespace

TEST(JointPhysics, SlidingSlowlyUnderLoadFollowsTheCapstanLaw) {
  // The tool presses hard tissue while the input advances slowly: tendon 1
  // slides towards the motor (T1 = T2 e^(mu Theta1)), tendon 2 away from it
  // (T4 = T3 e^(mu Theta2)).
  for (double wrap1 : {1.5, 3.4, 5.0}) {
    auto p = joint1();
    p.tendon1.wrap_rad = wrap1;
    p.tissue = hard_at(0.0);
    vts::JointPlant plant(p);
    drive(
        plant, [](double t) { return 0.05 * t; }, 6.0);  // 0.05 rad/s, well into the tissue
    const auto& t = plant.truth();
    ASSERT_GT(t.tau_out, 0.05) << "the tool should be loaded";
    const double mu = p.tendon1.mu;
    EXPECT_NEAR(t.T1 / t.T2, std::exp(mu * wrap1), 0.05 * std::exp(mu * wrap1)) << "wrap " << wrap1;
    EXPECT_NEAR(t.T4 / t.T3, std::exp(mu * p.tendon2.wrap_rad),
                0.05 * std::exp(mu * p.tendon2.wrap_rad));
  }
}

TEST(JointPhysics, DeadZoneAtReversalGrowsWithFrictionAndCompliance) {
  auto p = joint1();
  double previous = 0.0;
  for (double mu : {0.05, 0.1, 0.2}) {
    p.tendon1.mu = p.tendon2.mu = mu;
    const double dz = dead_zone(p);
    EXPECT_GT(dz, previous * 1.3) << "mu " << mu;
    previous = dz;
  }
  p = joint1();
  previous = 0.0;
  for (double ea : {8000.0, 4300.0, 2000.0}) {  // decreasing stiffness = more compliance
    p.tendon1.stiffness_ea_n = p.tendon2.stiffness_ea_n = ea;
    const double dz = dead_zone(p);
    EXPECT_GT(dz, previous * 1.3) << "EA " << ea;
    previous = dz;
  }
  // Without friction there is (almost) no dead zone: only the elastic lag of
  // accelerating the output.
  p = joint1();
  p.tendon1.mu = p.tendon2.mu = 0.0;
  EXPECT_LT(dead_zone(p), 0.01);
}

TEST(JointPhysics, HysteresisLoopHasThePaperScaleAndAsymmetry) {
  // The paper's Fig. 2(b): a 0.8 rad 0.5 Hz sine at the input gives a total friction
  // loop of about +10 N / -8.5 N. Joint1's sheaths differ (wrap 3.4 vs 1.2 rad).
  vts::JointPlant plant(joint1());
  double f_max = -1e9, f_min = 1e9;
  drive(
      plant, [](double t) { return 0.8 * std::sin(M_PI * t); }, 8.0,
      [&](double t) {
        if (t > 4.0) {
          f_max = std::max(f_max, plant.truth().friction);
          f_min = std::min(f_min, plant.truth().friction);
        }
      });
  EXPECT_NEAR(f_max, 10.0, 1.0);
  EXPECT_NEAR(f_min, -9.0, 1.0);
  EXPECT_GT(f_max + f_min, 0.5) << "the loop should be asymmetric";
}

TEST(JointPhysics, FrictionGrowsWithTheTransmittedLoad) {
  // Same slow motion in free space and pressing hard tissue: the sliding
  // friction is larger under load (the capstan effect the paper's model
  // lacks), by what the capstan law predicts from the distal tensions.
  auto sliding = [](bool loaded) {
    auto p = joint1();
    if (loaded) p.tissue = hard_at(-0.1);
    vts::JointPlant plant(p);
    drive(
        plant, [](double t) { return 0.1 * t; }, 8.0);
    return plant.truth();
  };
  const auto free_motion = sliding(false);
  const auto loaded = sliding(true);
  EXPECT_LT(std::abs(free_motion.tau_out), 0.02);
  EXPECT_GT(loaded.tau_out, 0.25);
  EXPECT_GT(loaded.friction, 1.25 * free_motion.friction);
  const auto p = joint1();
  const double predicted = loaded.T2 * (std::exp(p.tendon1.mu * p.tendon1.wrap_rad) - 1.0) +
                           loaded.T4 * (1.0 - std::exp(-p.tendon2.mu * p.tendon2.wrap_rad));
  EXPECT_NEAR(loaded.friction, predicted, 0.05 * predicted);
}

TEST(JointPhysics, LoadIndependentFrictionWhenCapstanIsOff) {
  auto sliding_friction = [](bool loaded) {
    auto p = joint1();
    if (loaded) p.tissue = hard_at(-0.1);
    vts::JointPlant plant(p);
    vts::FrictionEffects e;
    e.capstan = false;
    plant.set_effects(e);
    drive(
        plant, [](double t) { return 0.1 * t; }, 4.0);
    return plant.truth().friction;
  };
  EXPECT_NEAR(sliding_friction(true), sliding_friction(false), 0.05 * sliding_friction(false));
}

TEST(JointPhysics, ViscousEffectAddsFrictionProportionalToSpeed) {
  auto friction_at = [](double viscous, double speed) {
    vts::JointPlant plant(joint1());
    vts::FrictionEffects e;
    e.viscous = viscous;
    plant.set_effects(e);
    drive(
        plant, [&](double t) { return speed * t; }, 1.0);
    return plant.truth().friction;
  };
  const double extra = friction_at(1.0, 0.5) - friction_at(0.0, 0.5);
  EXPECT_NEAR(extra, 0.5, 0.05);  // 1 N per rad/s at 0.5 rad/s
}

TEST(JointPhysics, MoreWrapMeansMoreFrictionMidRun) {
  vts::JointPlant plant(joint1());
  drive(
      plant, [](double t) { return 0.2 * t; }, 1.5);
  const double before = plant.truth().friction;
  plant.set_wraps(5.0, 2.0);  // the endoscope bends
  drive(
      plant, [](double t) { return 0.3 + 0.2 * t; }, 1.5);
  EXPECT_GT(plant.truth().friction, before * 1.2);
}

TEST(JointPhysics, OutputWaitsWhileTheInputCrossesTheDeadZone) {
  // The backlash of Fig. 2(b): after a reversal the input travels back a
  // good way before the output moves at all.
  vts::JointPlant plant(joint1());
  drive(
      plant, [](double t) { return 0.3 * t; }, 2.0);
  double in_peak = -1.0, out_at_peak = 0.0, travel_still = 0.0;
  drive(
      plant, [](double t) { return 0.6 - 0.3 * t; }, 0.5,
      [&](double) {
        const auto& t = plant.truth();
        if (t.xd_in < 0 && in_peak < 0) {  // the input has turned
          in_peak = t.x_in;
          out_at_peak = t.x_out;
        }
        if (in_peak >= 0 && std::abs(t.x_out - out_at_peak) < 1e-5) travel_still = in_peak - t.x_in;
      });
  EXPECT_GT(travel_still, 0.05) << "input travel with the output standing still, rad";
}

TEST(JointPhysics, EnergyBalancesAndFrictionOnlyDissipates) {
  auto p = joint1();
  p.tissue = vts::tissue_preset("soft");
  p.tissue.surface_rad = 0.3;
  vts::JointPlant plant(p);
  // Shake the input, then let go (zero motor torque) and watch it ring down:
  // stored energy plus what went into the tissue never grows.
  drive(
      plant, [](double t) { return 0.5 * std::sin(2.0 * M_PI * 1.5 * t); }, 2.0);
  const double start = plant.stored_energy() + plant.energy().tissue_work;
  double previous = start, worst_rise = 0.0;
  for (int k = 0; k < 20000; ++k) {
    plant.step(0.0, vts::testing::kPhysicsDt);
    const double now = plant.stored_energy() + plant.energy().tissue_work;
    worst_rise = std::max(worst_rise, now - previous);
    previous = now;
  }
  EXPECT_LT(previous, start);
  EXPECT_LT(worst_rise, 1e-3 * start) << "energy rose in one step";
  const auto& e = plant.energy();
  EXPECT_GT(e.friction_dissipated, 0.0);
  EXPECT_GT(e.damping_dissipated, 0.0);
  // Work in = stored + dissipated + given to the tissue, to integration accuracy.
  const double balance = e.motor_work - plant.stored_energy() - e.friction_dissipated -
                         e.damping_dissipated - e.tissue_work;
  EXPECT_LT(std::abs(balance), 0.02 * e.motor_work) << "motor work " << e.motor_work;
}

TEST(JointPhysics, NoFallbackSolvesInOrdinaryMotion) {
  auto p = joint1();
  p.tissue = hard_at(0.3);
  vts::JointPlant plant(p);
  drive(
      plant, [](double t) { return 0.8 * std::sin(M_PI * t) + 0.05 * std::sin(37.0 * t); }, 6.0);
  EXPECT_EQ(plant.fallback_solves(), 0);
}
