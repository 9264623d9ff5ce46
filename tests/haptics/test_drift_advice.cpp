// The drift warning explains itself: what it saw, the likely cause for the
// direction of the mismatch, and only the recalibration means this setup has.
#include <gtest/gtest.h>

#include "haptics/drift_advice.hpp"

namespace tsmh::haptics {
namespace {

bool has(const std::string& s, const std::string& part) {
  return s.find(part) != std::string::npos;
}

TEST(DriftAdvice, LowScaleOnThePaperPresetNamesThePresetAndNoButtonTheMasterLacks) {
  const auto s = drift_advice(
      0, 0.22,
      {.config_path = "robot.yaml", .master_has_calibrate_button = false, .paper_preset = true});
  EXPECT_TRUE(has(s, "joint1")) << s;  // the name users see, 1-based
  EXPECT_TRUE(has(s, "0.22x")) << s;
  EXPECT_TRUE(has(s, "Less friction")) << s;
  EXPECT_TRUE(has(s, "`paper` preset")) << s;
  EXPECT_TRUE(has(s, "haptic-server --config robot.yaml --request-recalibration")) << s;
  EXPECT_TRUE(has(s, "tsm fit")) << s;
  EXPECT_FALSE(has(s, "button")) << s;
}

TEST(DriftAdvice, HighScaleNamesAReRouteAndTheButtonWhenTheMasterHasOne) {
  const auto s = drift_advice(
      1, 1.5, {.config_path = "", .master_has_calibrate_button = true, .paper_preset = false});
  EXPECT_TRUE(has(s, "joint2")) << s;
  EXPECT_TRUE(has(s, "More friction")) << s;
  EXPECT_TRUE(has(s, "re-routed")) << s;
  EXPECT_FALSE(has(s, "preset")) << s;
  EXPECT_TRUE(has(s, "recalibrate button")) << s;
  EXPECT_TRUE(has(s, "--config FILE --request-recalibration")) << s;
}

}  // namespace
}  // namespace tsmh::haptics
