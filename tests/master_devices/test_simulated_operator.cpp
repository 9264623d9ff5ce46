// The operator hand model, and the property the demo relies on: pressing
// into a stiffer virtual wall with feedback on moves the hand less than
// with feedback off.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "master_devices/sim_device.hpp"
#include "master_devices/simulated_operator.hpp"

namespace tsmh::master_devices {
namespace {

TEST(SimulatedOperator, FollowsASlowIntentionWithoutFeedback) {
  SineScenario s;
  s.amplitude_rad = {0.3, 0.2};
  s.frequency_hz = {0.2, 0.1};
  SimulatedOperator op(s, 2);
  double worst = 0;
  for (int k = 0; k < 10000; ++k) {
    op.step(0.001, JointArray{});
    if (k > 2000) worst = std::max(worst, std::abs(op.q()[0] - op.intention().q[0]));
  }
  EXPECT_LT(worst, 0.02);
}

TEST(SimulatedOperator, AConstantTorqueShiftsTheHandByTorqueOverArmStiffness) {
  StepScenario hold;  // intention 0 until 1 s
  hold.start_s = 100.0;
  HandParams hand;
  SimulatedOperator op(hold, 2, hand);
  for (int k = 0; k < 5000; ++k)
    op.step(0.001, JointArray{0.3, 0.0});
  EXPECT_NEAR(op.q()[0], 0.3 / hand.stiffness_nm_per_rad, 1e-3);
  EXPECT_NEAR(op.q()[1], 0.0, 1e-9);
}

// The server loop in miniature: the sim device in simulated time, a virtual
// wall at 0.05 rad rendered at 1 kHz, the operator pressing to 0.3 rad.
double deepest_press(double wall_stiffness, bool feedback) {
  SimSettings s;
  s.simulated_time = true;
  StepScenario press;
  press.amplitude_rad = {0.3, 0.0};
  press.start_s = 0.5;
  press.high_s = 3.0;
  press.low_s = 1.0;
  press.repeats = 1;
  s.scenario = press;
  s.peak_torque_nm.fill(2.0);
  s.continuous_torque_nm.fill(1.0);
  SimDevice dev(s);
  dev.open();
  dev.set_enabled(true);
  const double wall = 0.05;
  double deepest = 0;
  for (std::int64_t k = 0; k < 4000; ++k) {
    const DeviceReading r = dev.read(k * 1'000'000);
    EXPECT_EQ(r.status, DeviceStatus::kOk);
    deepest = std::max(deepest, r.q[0]);
    const double penetration = std::max(0.0, r.q[0] - wall);
    const double tau = -wall_stiffness * penetration;
    dev.write_torque(JointArray{feedback ? tau : 0.0, 0.0});
  }
  return deepest;
}

TEST(SimulatedOperator, PressingAStifferWallWithFeedbackMovesTheHandLess) {
  const double off = deepest_press(3.0, false);
  const double soft = deepest_press(0.5, true);
  const double stiff = deepest_press(3.0, true);
  EXPECT_NEAR(off, 0.3, 0.05) << "without feedback the hand goes where it wants";
  EXPECT_LT(stiff, off);
  EXPECT_LT(soft, off);
  EXPECT_LT(stiff, soft) << "a stiffer wall stops the hand sooner";
  // Static balance: k_arm (0.3 - q) = K (q - 0.05) -> q = (0.9 + 0.15) / 6 = 0.175 for K = 3.
  EXPECT_NEAR(stiff, 0.175, 0.03);
}

TEST(SimulatedOperator, ResetReturnsToTheStart) {
  SimulatedOperator op(PalpateScenario{}, 2);
  for (int k = 0; k < 3000; ++k)
    op.step(0.001, JointArray{});
  EXPECT_GT(op.time_s(), 2.9);
  op.reset();
  EXPECT_EQ(op.time_s(), 0.0);
  EXPECT_EQ(op.q()[0], 0.0);
}

}  // namespace
}  // namespace tsmh::master_devices
