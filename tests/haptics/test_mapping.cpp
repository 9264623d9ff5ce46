// Force and position mapping: the reaction rendered, the clutch, the workspace.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "haptics/force_mapping.hpp"
#include "haptics/position_mapping.hpp"

namespace tsmh::haptics {
namespace {

TEST(ForceMapping, ScaleSignAndContinuousDeadband) {
  const ForceMapping m{2.0, -1.0, 0.01};
  EXPECT_DOUBLE_EQ(m(0.005), 0.0);
  EXPECT_DOUBLE_EQ(m(0.01), 0.0);
  EXPECT_NEAR(m(0.03), 2.0 * 0.02, 1e-15);
  EXPECT_NEAR(m(-0.03), -2.0 * 0.02, 1e-15);
  EXPECT_TRUE(std::isnan(m(std::nan(""))));  // left for the safety filter to catch
}

TEST(ForceMapping, RendersTheReactionThatPushesTheHandOutOfTheTissue) {
  // Joints turning the same way: the tool presses in + (positive distal
  // torque), so the hand, which moved the master in +, is pushed back in -.
  EXPECT_LT((ForceMapping{1.0, 1.0, 0.0})(0.2), 0.0);
  EXPECT_GT((ForceMapping{1.0, 1.0, 0.0})(-0.2), 0.0);
  // Opposite conventions: the master moved in - to press in +; pushed back in +.
  EXPECT_GT((ForceMapping{1.0, -1.0, 0.0})(0.2), 0.0);
}

TEST(PositionMapping, ClutchFreezesThenContinuesWithoutJump) {
  PositionMapping p({.scale = 0.5, .sign = 1.0});
  EXPECT_DOUBLE_EQ(p.update(0.2, false), 0.1);
  EXPECT_DOUBLE_EQ(p.update(0.4, true), 0.1);  // clutched: frozen
  EXPECT_DOUBLE_EQ(p.update(1.0, true), 0.1);
  EXPECT_DOUBLE_EQ(p.update(1.0, false), 0.1);  // released: no jump
  EXPECT_DOUBLE_EQ(p.update(1.2, false), 0.2);  // then follows with the new offset
  EXPECT_DOUBLE_EQ(p.update(std::nan(""), false), 0.2);
}

TEST(PositionMapping, ClampsToSlaveWorkspace) {
  PositionMapping p({.scale = 1.0, .sign = -1.0, .min_ref = -0.5, .max_ref = 0.5});
  EXPECT_DOUBLE_EQ(p.update(2.0, false), -0.5);
  EXPECT_DOUBLE_EQ(p.update(-0.3, false), 0.3);
}

}  // namespace
}  // namespace tsmh::haptics
