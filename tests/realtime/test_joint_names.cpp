// One name per joint: joint1, joint2, ... wherever a user sees or types one;
// the old 0-based index is still accepted where a joint is typed.
#include <gtest/gtest.h>

#include "realtime/joint_names.hpp"

namespace tsmh::realtime {
namespace {

TEST(JointNames, NamesAreOneBased) {
  EXPECT_EQ(joint_name(0), "joint1");
  EXPECT_EQ(joint_name(1), "joint2");
  EXPECT_EQ(joint_name(7), "joint8");
}

TEST(JointNames, ATypedJointIsItsNameOrItsOldIndex) {
  EXPECT_EQ(joint_from_text("joint1", 2), 0u);
  EXPECT_EQ(joint_from_text("joint2", 2), 1u);
  EXPECT_EQ(joint_from_text("0", 2), 0u);  // the 0-based index earlier versions took
  EXPECT_EQ(joint_from_text("1", 2), 1u);
  EXPECT_FALSE(joint_from_text("joint3", 2));
  EXPECT_FALSE(joint_from_text("2", 2));
  EXPECT_FALSE(joint_from_text("joint0", 2));
  EXPECT_FALSE(joint_from_text("joint", 2));
  EXPECT_FALSE(joint_from_text("", 2));
  EXPECT_FALSE(joint_from_text("-1", 2));
  EXPECT_FALSE(joint_from_text("joint1x", 2));
  EXPECT_FALSE(joint_from_text("Joint1", 2));
}

}  // namespace
}  // namespace tsmh::realtime
