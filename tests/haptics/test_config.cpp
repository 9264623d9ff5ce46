// Server configuration: defaults, and every bad field named in the error.
#include <gtest/gtest.h>

#include "haptics/evaluation.hpp"
#include "haptics/server_config.hpp"

namespace tsmh::haptics {
namespace {

const std::string kJoint = "joints:\n  - {name: a, max_torque_nm: 0.3}\n";

std::string error_of(const std::string& yaml) {
  try {
    parse_server_config(yaml, "server.yaml", "/cfg");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ServerConfig, DefaultsAreSafe) {
  const auto c = parse_server_config(kJoint, "server.yaml", "/cfg");
  EXPECT_EQ(c.loop.joints, 1);
  EXPECT_DOUBLE_EQ(c.loop.rate_hz, 1000.0);
  EXPECT_EQ(c.loop.status_every, 10);
  EXPECT_EQ(c.loop.source, FeedbackSource::kEstimated);
  EXPECT_DOUBLE_EQ(c.loop.timing.stale_after_s, 0.020);
  EXPECT_DOUBLE_EQ(c.loop.limits[0].max_torque_nm, 0.3);
  EXPECT_EQ(c.device_driver, "sim");
  EXPECT_EQ(c.joints[0].params, "paper");
  EXPECT_FALSE(c.evaluation.truth);
}

TEST(ServerConfig, RelativePathsResolveAgainstTheConfigFolder) {
  const auto c = parse_server_config(
      "joints:\n  - {params: fits/j0.yaml, max_torque_nm: 0.3}\nevaluation: {trace: out/t.csv}\n",
      "server.yaml", "/cfg");
  EXPECT_EQ(c.joints[0].params, "/cfg/fits/j0.yaml");
  EXPECT_EQ(c.evaluation.trace, "/cfg/out/t.csv");
}

TEST(ServerConfig, BadFieldsAreNamed) {
  EXPECT_NE(error_of("joints:\n  - {name: a}\n").find("joints[0].max_torque_nm: missing"),
            std::string::npos);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: -1}\n").find("joints[0].max_torque_nm"),
            std::string::npos);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: .nan}\n").find("joints[0].max_torque_nm"),
            std::string::npos);
  EXPECT_NE(
      error_of("joints:\n  - {max_torque_nm: 1, force_sign: 2}\n").find("joints[0].force_sign:"),
      std::string::npos);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: 1, force_sign: 0.5}\n")
                .find("joints[0].force_sign: must be 1 or -1"),
            std::string::npos);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: 1, torque_max: 2}\n")
                .find("joints[0].torque_max: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of("rate_hz: 9000\n" + kJoint).find("rate_hz"), std::string::npos);
  EXPECT_NE(error_of("feedback: loud\n" + kJoint).find("feedback: 'loud'"), std::string::npos);
  EXPECT_NE(error_of("safety: {stale_after_ms: 0}\n" + kJoint).find("safety.stale_after_ms"),
            std::string::npos);
  EXPECT_NE(error_of("lcm: {url: [1, 2]}\n" + kJoint).find("lcm.url: must be a string"),
            std::string::npos);
  EXPECT_NE(error_of("realtime: {sched_fifo: maybe}\n" + kJoint).find("realtime.sched_fifo"),
            std::string::npos);
  EXPECT_NE(error_of("joints: []\n").find("joints: missing"), std::string::npos);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: 1, slave_min_rad: 1, slave_max_rad: 0}\n")
                .find("joints[0].slave_min_rad"),
            std::string::npos);
  EXPECT_NE(error_of("rate_hz: [\n").find("not valid YAML"), std::string::npos);
  EXPECT_NE(error_of("colour: blue\n" + kJoint).find("colour: unknown key"), std::string::npos);
}

TEST(Evaluation, SlopeOfALine) {
  EXPECT_NEAR(slope({0, 1, 2, 3}, {1, 3, 5, 7}), 2.0, 1e-12);
  EXPECT_TRUE(std::isnan(slope({1, 1, 1}, {1, 2, 3})));
  EXPECT_TRUE(std::isnan(slope({1}, {1})));
}

}  // namespace
}  // namespace tsmh::haptics
