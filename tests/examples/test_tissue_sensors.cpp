// Tissue contact laws and presets; sensors.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "virtual_tissue_slave/sensors.hpp"
#include "virtual_tissue_slave/tissue.hpp"

namespace vts = tsmh::virtual_tissue_slave;

TEST(Tissue, PresetsHaveTheDocumentedJointSpaceStiffness) {
  const auto soft = vts::tissue_truth(vts::tissue_preset("soft"));
  const auto hard = vts::tissue_truth(vts::tissue_preset("hard"));
  const auto nodule = vts::tissue_truth(vts::tissue_preset("nodule"));
  EXPECT_NEAR(soft.outer_nm_per_rad, 0.2, 1e-12);
  EXPECT_NEAR(hard.outer_nm_per_rad, 1.5, 1e-12);
  EXPECT_NEAR(nodule.outer_nm_per_rad, 0.2, 1e-12);
  EXPECT_NEAR(nodule.inclusion_nm_per_rad, 1.5, 1e-12);
  EXPECT_NEAR(nodule.inclusion_depth_rad, 0.15, 1e-12);
  EXPECT_NEAR(soft.outer_n_per_m * 0.03 * 0.03, soft.outer_nm_per_rad, 1e-12);
  EXPECT_EQ(hard.inclusion_depth_m, 0.0);
  EXPECT_FALSE(vts::tissue_preset("none").present);
}

TEST(Tissue, NoduleHasTheSoftSlopeThenTheHardSlope) {
  auto t = vts::tissue_preset("nodule");
  t.surface_rad = 0.2;
  const double k_soft = t.outer_stiffness_n_per_m, k_hard = t.inclusion_stiffness_n_per_m;
  const double d = t.inclusion_depth_m;
  EXPECT_NEAR(vts::elastic_force(t, 0.5 * d) / (0.5 * d), k_soft, 1e-9);
  const double slope_deep =
      (vts::elastic_force(t, 2.0 * d) - vts::elastic_force(t, 1.5 * d)) / (0.5 * d);
  EXPECT_NEAR(slope_deep, k_hard, 1e-6);
  // Continuous at the inclusion.
  EXPECT_NEAR(vts::elastic_force(t, d * (1 + 1e-9)), vts::elastic_force(t, d), 1e-6);
  // Contact state reports the local slope in joint space.
  const auto shallow = vts::contact(t, 0.2 + 0.05, 0.0);
  const auto deep = vts::contact(t, 0.2 + 0.3, 0.0);
  EXPECT_NEAR(shallow.stiffness_nm_per_rad, 0.2, 1e-9);
  EXPECT_NEAR(deep.stiffness_nm_per_rad, 1.5, 1e-9);
  EXPECT_NEAR(deep.torque_nm, 0.03 * deep.force_n, 1e-12);
}

TEST(Tissue, ContactIsOneSided) {
  for (auto law : {vts::ContactLaw::kKelvinVoigt, vts::ContactLaw::kHuntCrossley}) {
    auto t = vts::tissue_preset("hard", law);
    t.surface_rad = 0.0;
    EXPECT_EQ(vts::contact(t, -0.1, 0.0).force_n, 0.0);    // not touching
    EXPECT_GE(vts::contact(t, 0.01, -50.0).force_n, 0.0);  // fast retract: no pull
    EXPECT_GT(vts::contact(t, 0.05, 0.0).force_n, 0.0);
  }
}

TEST(Tissue, HuntCrossleyHasNoForceJumpAtImpact) {
  auto hc = vts::tissue_preset("hard", vts::ContactLaw::kHuntCrossley);
  auto kv = vts::tissue_preset("hard", vts::ContactLaw::kKelvinVoigt);
  hc.surface_rad = kv.surface_rad = 0.0;
  const double q = 1e-6, qd = 2.0;  // just touching, fast
  EXPECT_LT(vts::contact(hc, q, qd).force_n, 1e-3);
  EXPECT_GT(vts::contact(kv, q, qd).force_n, 0.1);  // Kelvin-Voigt jumps by c * velocity
  // Hunt-Crossley: more force pressing in than pulling out at the same depth.
  EXPECT_GT(vts::contact(hc, 0.1, 1.0).force_n, vts::contact(hc, 0.1, -1.0).force_n);
}

TEST(Tissue, UnknownNamesAreClearErrors) {
  try {
    vts::tissue_preset("jelly");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("jelly"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("nodule"), std::string::npos);
  }
  EXPECT_THROW(vts::parse_contact_law("spring"), std::invalid_argument);
  auto t = vts::tissue_preset("soft");
  t.lever_m = 0.0;
  EXPECT_THROW(vts::validate(t), std::invalid_argument);
}

TEST(Sensors, EncodersQuantiseAndLoadCellsAreNoisy) {
  vts::SensorParams p;
  p.load_cell_noise_n = 0.05;
  vts::Sensors sensors(p, 3);
  vts::JointTruth truth;
  truth.x_in = 0.123456789;
  truth.x_out = -0.0987654321;
  truth.T1 = 20.0;
  truth.T3 = 18.0;
  double sum = 0.0, sum2 = 0.0;
  const int n = 20000;
  for (int i = 0; i < n; ++i) {
    const auto m = sensors.measure(truth);
    const double counts = m.x_in / p.motor_encoder_quantum_rad;
    ASSERT_NEAR(counts, std::round(counts), 1e-6);
    ASSERT_NEAR(m.x_in, truth.x_in, 0.5 * p.motor_encoder_quantum_rad + 1e-15);
    ASSERT_NEAR(m.x_out, truth.x_out, 0.5 * p.joint_encoder_quantum_rad + 1e-15);
    sum += m.T1 - truth.T1;
    sum2 += (m.T1 - truth.T1) * (m.T1 - truth.T1);
  }
  const double mean = sum / n;
  const double sd = std::sqrt(sum2 / n - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.005);
  EXPECT_NEAR(sd, 0.05, 0.005);
}

TEST(Sensors, NoJointEncoderReadsNaNAndSeedsReproduce) {
  vts::SensorParams p;
  p.joint_encoder = false;
  vts::Sensors a(p, 9), b(p, 9);
  vts::JointTruth truth;
  truth.T1 = 10.0;
  const auto ma = a.measure(truth);
  const auto mb = b.measure(truth);
  EXPECT_TRUE(std::isnan(ma.x_out));
  EXPECT_EQ(ma.T1, mb.T1);
  p.load_cell_noise_n = -1.0;
  EXPECT_THROW(vts::Sensors(p, 1), std::invalid_argument);
}

// The log line names what each angle is: a bare "nodule at 0.200 rad" was
// read as the nodule's place, though 0.200 rad is the tissue surface.
TEST(Tissue, DescriptionNamesTheSurfaceAndTheInclusion) {
  const std::string d = vts::tissue_description(vts::tissue_preset("nodule"));
  EXPECT_NE(d.find("surface at joint angle 0.300 rad"), std::string::npos) << d;
  EXPECT_NE(d.find("from joint angle 0.450 rad"), std::string::npos) << d;
  EXPECT_NE(d.find("1.500 N m/rad"), std::string::npos) << d;
  EXPECT_EQ(vts::tissue_description(vts::tissue_preset("none")).find("rad"), std::string::npos);
}
