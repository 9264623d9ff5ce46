// MASTER_COMMAND handling: follow fresh enabled commands, hold otherwise.

#include <gtest/gtest.h>

#include "virtual_tissue_slave/command_gate.hpp"
#include "virtual_tissue_slave/slave.hpp"

namespace vts = tsmh::virtual_tissue_slave;

namespace {
vts::CommandView command(double ref, double age = 0.0, bool enable = true, bool clutch = false) {
  vts::CommandView c;
  c.version = 1;
  c.age_s = age;
  c.enable = enable;
  c.clutch = clutch;
  c.position_ref = {ref, -ref};
  return c;
}
}  // namespace

TEST(CommandGate, HoldsUntilTheFirstCommand) {
  vts::CommandGate gate({}, {0.1, 0.2});
  const auto& r = gate.update(vts::CommandView{}, 0.001);
  EXPECT_EQ(r[0], 0.1);
  EXPECT_EQ(r[1], 0.2);
  EXPECT_EQ(gate.status(), vts::kStatusHolding);
}

TEST(CommandGate, FollowsFreshCommandsRateLimited) {
  vts::CommandGateParams p;
  p.max_velocity_rad_s = 2.0;
  vts::CommandGate gate(p, {0.0, 0.0});
  gate.update(command(1.0), 0.001);
  EXPECT_NEAR(gate.reference()[0], 0.002, 1e-12);  // a 1 rad jump becomes a ramp
  EXPECT_NEAR(gate.reference()[1], -0.002, 1e-12);
  EXPECT_EQ(gate.status(), vts::kStatusEnabled);
  for (int i = 0; i < 1000; ++i)
    gate.update(command(1.0), 0.001);
  EXPECT_NEAR(gate.reference()[0], 1.0, 1e-12);
}

TEST(CommandGate, HoldsWhenStaleDisabledClutchedOrNonFinite) {
  vts::CommandGate gate({}, {0.0, 0.0});
  for (int i = 0; i < 200; ++i)
    gate.update(command(0.3), 0.001);
  const double held = gate.reference()[0];
  EXPECT_NEAR(held, 0.3, 1e-12);
  gate.update(command(0.9, 0.5), 0.001);  // older than the 0.1 s timeout
  EXPECT_EQ(gate.reference()[0], held);
  EXPECT_EQ(gate.status(), vts::kStatusHolding);
  gate.update(command(0.9, 0.0, false), 0.001);
  EXPECT_EQ(gate.reference()[0], held);
  gate.update(command(0.9, 0.0, true, true), 0.001);
  EXPECT_EQ(gate.reference()[0], held);
  gate.update(command(std::nan("")), 0.001);
  EXPECT_EQ(gate.reference()[0], held);
}

TEST(CommandGate, ClampsToTheJointRange) {
  vts::CommandGateParams p;
  p.max_velocity_rad_s = 1e4;
  vts::CommandGate gate(p, {0.0, 0.0});
  gate.update(command(5.0), 0.001);
  EXPECT_EQ(gate.reference()[0], p.max_rad);
  EXPECT_EQ(gate.reference()[1], p.min_rad);
}

TEST(CommandGate, TheSlaveHoldsItsPositionWhenCommandsStop) {
  vts::SlaveParams params = vts::paper_slave();
  vts::VirtualSlave slave(params, 1);
  slave.settle({0.0, 0.0}, 0.3);
  vts::CommandGate gate({}, {0.0, 0.0});
  // 2 s of a moving command, then silence for 3 s.
  for (int k = 0; k < 2000; ++k)
    slave.tick(gate.update(command(0.5 * std::sin(3.0 * k * 0.001)), 0.001));
  double lo = 1e9, hi = -1e9;
  for (int k = 0; k < 3000; ++k) {
    const double age = 0.001 * (k + 1);  // the last command ages; after 0.1 s it is stale
    slave.tick(gate.update(command(0.5 * std::sin(3.0 * (2.0 + age)), age), 0.001));
    if (k >= 1000) {
      lo = std::min(lo, slave.joint(0).truth().x_out);
      hi = std::max(hi, slave.joint(0).truth().x_out);
    }
  }
  EXPECT_EQ(gate.status(), vts::kStatusHolding);
  // It settles onto the frozen reference and stays there.
  EXPECT_NEAR(slave.joint(0).truth().x_out, gate.reference()[0], 0.005);
  EXPECT_LT(hi - lo, 0.002) << "the held joint drifts";
}
