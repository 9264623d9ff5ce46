// The mapping layer: a master's own coordinates (joints, or a handle through
// its kinematics) to the slave's joints and back. A simulated 3-DOF Cartesian
// master (the Falcon profile) drives a 2-DOF slave; the Haply 2DIY's
// pantograph kinematics against finite differences and virtual work.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "master_devices/axis_mapping.hpp"

namespace tsmh::master_devices {
namespace {

const std::filesystem::path kMasters =
    std::filesystem::path(TSMH_SOURCE_DIR) / "master_devices/profiles/masters";

MasterProfile falcon() {
  return load_master_profile(kMasters / "novint-falcon.yaml");
}
MasterProfile haply() {
  return load_master_profile(kMasters / "haply-2diy.yaml");
}

MappingConfig mapping(const MasterProfile& p, const std::string& yaml) {
  return parse_mapping(YAML::Load(yaml), p, "test.yaml", "mapping");
}

// The handle position q for an identity (Cartesian) master.
JointArray at(double x, double y, double z) {
  JointArray q{};
  q[0] = x;
  q[1] = y;
  q[2] = z;
  return q;
}

constexpr const char* kFalconMap = R"(
joints:
  - {axis: x, scale: 10}
  - {axis: z, scale: -10, offset: 0.1}
buttons: {dead_man: center, clutch: left, calibrate: right}
)";

TEST(AxisMapping, CartesianMasterDrivesTwoSlaveJointsByScaledAxes) {
  const auto p = falcon();
  MasterMapping m(p, mapping(p, kFalconMap));
  ASSERT_EQ(m.slave_joints(), 2U);
  ASSERT_TRUE(m.update(at(0.02, 0.03, -0.01), 0));
  EXPECT_NEAR(m.slave_position()[0], 0.2, 1e-12);
  EXPECT_NEAR(m.slave_position()[1], 0.1 + 0.1, 1e-12);  // -10 x -0.01 + offset
  // y is not mapped: moving it moves nothing.
  ASSERT_TRUE(m.update(at(0.02, -0.04, -0.01), 0));
  EXPECT_NEAR(m.slave_position()[0], 0.2, 1e-12);
  // Outside the workspace the handle reads at its edge.
  ASSERT_TRUE(m.update(at(0.09, 0.0, 0.0), 0));
  EXPECT_NEAR(m.handle()[0], 0.05, 1e-12);
  EXPECT_NEAR(m.slave_position()[0], 0.5, 1e-12);
}

TEST(AxisMapping, ClutchHoldsTheSlaveAndReleasesWithoutAJump) {
  const auto p = falcon();
  MasterMapping m(p, mapping(p, kFalconMap));
  const std::uint32_t clutch = 1U << 1;  // "left"
  ASSERT_TRUE(m.update(at(0.01, 0, 0), 0));
  EXPECT_NEAR(m.slave_position()[0], 0.1, 1e-12);
  ASSERT_TRUE(m.update(at(0.01, 0, 0), clutch));
  EXPECT_TRUE(m.buttons().clutch);
  ASSERT_TRUE(m.update(at(-0.03, 0, 0), clutch));  // re-index the hand
  EXPECT_NEAR(m.slave_position()[0], 0.1, 1e-12) << "held during the clutch";
  ASSERT_TRUE(m.update(at(-0.03, 0, 0), 0));
  EXPECT_NEAR(m.slave_position()[0], 0.1, 1e-12) << "no jump on release";
  ASSERT_TRUE(m.update(at(-0.02, 0, 0), 0));
  EXPECT_NEAR(m.slave_position()[0], 0.2, 1e-12) << "follows again from where it held";
}

TEST(AxisMapping, SlaveTorqueReachesTheHandleByVirtualWorkWithinItsLimits) {
  const auto p = falcon();
  MasterMapping m(p, mapping(p, kFalconMap));
  ASSERT_TRUE(m.update(at(0, 0, 0), 0));
  JointArray tau{};
  tau[0] = 0.2;
  tau[1] = 0.1;
  auto f = m.handle_force(tau);
  EXPECT_NEAR(f[0], 2.0, 1e-12);
  EXPECT_NEAR(f[1], 0.0, 1e-12);
  EXPECT_NEAR(f[2], -1.0, 1e-12);
  // Power balance: f . dx = tau . dv for a small handle motion.
  const JointArray v0 = m.slave_position();
  ASSERT_TRUE(m.update(at(1e-4, 0, 2e-4), 0));
  const double pw_handle = f[0] * 1e-4 + f[2] * 2e-4;
  const double pw_slave =
      tau[0] * (m.slave_position()[0] - v0[0]) + tau[1] * (m.slave_position()[1] - v0[1]);
  EXPECT_NEAR(pw_handle, pw_slave, 1e-12);
  // Too much: scaled down to the 8.9 N limit, keeping the direction.
  tau[0] = 5.0;
  tau[1] = 1.0;
  f = m.handle_force(tau);
  EXPECT_NEAR(f[0], 8.9, 1e-9);
  EXPECT_NEAR(f[2], -8.9 / 5.0, 1e-9);
  tau[1] = std::nan("");
  f = m.handle_force(tau);
  EXPECT_EQ(f, JointArray{});
}

TEST(AxisMapping, ButtonsAreMappedByName) {
  const auto p = falcon();
  MasterMapping m(p, mapping(p, kFalconMap));
  ASSERT_TRUE(m.update(at(0, 0, 0), 1U << 0 | 1U << 3));  // center + right
  EXPECT_TRUE(m.buttons().dead_man);
  EXPECT_TRUE(m.buttons().calibrate);
  EXPECT_FALSE(m.buttons().clutch);
  EXPECT_FALSE(m.buttons().e_stop);
  ASSERT_TRUE(m.update(at(0, 0, 0), 1U << 2));  // forward: no role
  EXPECT_EQ(m.buttons(), Buttons{});
}

TEST(AxisMapping, UnknownNamesAreErrorsNamingTheFieldAndTheKnownNames) {
  const auto p = falcon();
  try {
    mapping(p, "joints: [{axis: w}]");
    FAIL() << "accepted axis w";
  } catch (const config::ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("mapping.joints[0].axis"), std::string::npos) << what;
    EXPECT_NE(what.find("x, y, z"), std::string::npos) << what;
  }
  try {
    mapping(p, "joints: [{axis: x}]\nbuttons: {clutch: trigger}");
    FAIL() << "accepted button trigger";
  } catch (const config::ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("clutch"), std::string::npos) << what;
    EXPECT_NE(what.find("center, left, forward, right"), std::string::npos) << what;
  }
  EXPECT_THROW(parse_master_profile("name: a\nupdate_rate_hz: 1000\nkinematics: {type: delta, "
                                    "joints: 3}\n",
                                    "p.yaml"),
               config::ConfigError);
}

// Central differences of the forward kinematics.
Jacobian numeric_jacobian(const KinematicsSpec& k, JointArray q) {
  Jacobian J{};
  const double h = 1e-7;
  for (std::size_t j = 0; j < 2; ++j) {
    JointArray xp, xm;
    Jacobian unused;
    q[j] += h;
    EXPECT_TRUE(forward_kinematics(k, q, xp, unused));
    q[j] -= 2 * h;
    EXPECT_TRUE(forward_kinematics(k, q, xm, unused));
    q[j] += h;
    for (std::size_t i = 0; i < 2; ++i)
      J[i][j] = (xp[i] - xm[i]) / (2 * h);
  }
  return J;
}

TEST(PantographKinematics, HandleClosesBothLoopsAndTheJacobianMatchesFiniteDifferences) {
  const auto p = haply();
  const auto& g = p.kinematics.pantograph;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> t1(1.6, 2.6), t2(0.5, 1.5);  // elbows out, handle up
  int solved = 0;
  for (int n = 0; n < 200; ++n) {
    JointArray q{};
    q[0] = t1(rng);
    q[1] = t2(rng);
    JointArray x;
    Jacobian J;
    if (!forward_kinematics(p.kinematics, q, x, J)) continue;
    ++solved;
    const double ax = g.l_m * std::cos(q[0]), ay = g.l_m * std::sin(q[0]);
    const double bx = g.d_m + g.l_m * std::cos(q[1]), by = g.l_m * std::sin(q[1]);
    EXPECT_NEAR(std::hypot(x[0] - ax, x[1] - ay), g.L_m, 1e-12);
    EXPECT_NEAR(std::hypot(x[0] - bx, x[1] - by), g.L_m, 1e-12);
    const auto Jn = numeric_jacobian(p.kinematics, q);
    for (int i = 0; i < 2; ++i)
      for (int j = 0; j < 2; ++j)
        EXPECT_NEAR(J[i][j], Jn[i][j], 1e-6) << i << j << " n " << n;
  }
  EXPECT_EQ(solved, 200) << "every pose of this range has a handle position";
  // Short distal links cannot close the loop with the elbows far apart.
  KinematicsSpec short_links = p.kinematics;
  short_links.pantograph.L_m = 0.05;
  JointArray far{};
  far[0] = M_PI;
  far[1] = 0.0;
  JointArray x{}, x_before{};
  Jacobian J{};
  EXPECT_FALSE(forward_kinematics(short_links, far, x, J));
  EXPECT_EQ(x, x_before) << "untouched where there is no solution";
  far[1] = std::nan("");
  EXPECT_FALSE(forward_kinematics(p.kinematics, far, x, J));
}

TEST(PantographKinematics, TwoDiyRendersThroughTheJacobianTransposeWithinItsTorqueLimits) {
  const auto p = haply();
  const auto cfg = mapping(p,
                           "joints: [{axis: x, scale: 8}, {axis: y, scale: 8}]\n"
                           "buttons: {dead_man: held}");
  MasterMapping m(p, cfg);
  JointArray q{};
  q[0] = 2.0;
  q[1] = 1.0;
  ASSERT_TRUE(m.update(q, 0));
  EXPECT_TRUE(m.buttons().dead_man);
  JointArray tau{};
  tau[0] = 0.1;
  tau[1] = -0.05;
  const auto f = m.handle_force(tau);
  const auto t = m.joint_torques(tau);
  JointArray x;
  Jacobian J;
  ASSERT_TRUE(forward_kinematics(p.kinematics, q, x, J));
  for (int j = 0; j < 2; ++j)
    EXPECT_NEAR(t[j], J[0][j] * f[0] + J[1][j] * f[1], 1e-12);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> big(-100, 100), ang1(1.6, 2.6), ang2(0.5, 1.5);
  for (int n = 0; n < 1000; ++n) {
    q[0] = ang1(rng);
    q[1] = ang2(rng);
    tau[0] = big(rng);
    tau[1] = big(rng);
    ASSERT_TRUE(m.update(q, 0));
    const auto fl = m.handle_force(tau);
    const auto tl = m.joint_torques(tau);
    for (int k = 0; k < 2; ++k)
      EXPECT_LE(std::abs(fl[k]), p.force_limit[k] + 1e-12);
    for (int j = 0; j < 2; ++j)
      EXPECT_LE(std::abs(tl[j]), p.joint_torque_limit_nm[j] + 1e-12);
  }
}

}  // namespace
}  // namespace tsmh::master_devices
