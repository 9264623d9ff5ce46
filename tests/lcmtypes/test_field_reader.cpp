// config::FieldReader on its own (linked without master_devices or haptics):
// every error names source, field and line; unknown, duplicate and
// mistyped keys are refused.

#include <gtest/gtest.h>

#include <string>

#include "config/field_reader.hpp"

namespace tsmh::config {
namespace {

std::string error_of(void (*f)()) {
  try {
    f();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(FieldReader, ErrorNamesSourceFieldAndLine) {
  const std::string what = error_of([] {
    FieldReader r(YAML::Load("a: 1\nrate_hz: fast\n"), "server.yaml", "loop");
    r.get_double("rate_hz", 1000.0);
  });
  EXPECT_EQ(what, "server.yaml: loop.rate_hz: must be a number (line 2)");
}

TEST(FieldReader, UnknownKeyIsRefusedWithTheKnownOnes) {
  const std::string what = error_of([] {
    FieldReader r(YAML::Load("gain: 2\ngian: 3\n"), "device.yaml", "");
    r.get_positive("gain", 1.0);
    r.reject_unknown();
  });
  EXPECT_EQ(what, "device.yaml: gian: unknown key (expected one of: gain) (line 2)");
}

TEST(FieldReader, DuplicateKeyAnywhereIsRefused) {
  const std::string what = error_of([] {
    reject_duplicate_keys(YAML::Load("safety:\n  max_torque_nm: 0.3\n  max_torque_nm: 50\n"),
                          "server.yaml");
  });
  EXPECT_NE(what.find("server.yaml: safety.max_torque_nm: duplicate key"), std::string::npos)
      << what;
}

TEST(FieldReader, OneValuePerJointOrAList) {
  realtime::JointArray out{};
  FieldReader r(YAML::Load("scale: 2\nlimits: [1, 3]\n"), "x.yaml", "");
  r.get_joint_array("scale", out, 2);
  EXPECT_EQ(out[0], 2.0);
  EXPECT_EQ(out[1], 2.0);
  r.get_joint_array("limits", out, 2);
  EXPECT_EQ(out[1], 3.0);
  const std::string what = error_of([] {
    realtime::JointArray a{};
    FieldReader bad(YAML::Load("limits: [1, 2, 3]\n"), "x.yaml", "");
    bad.get_joint_array("limits", a, 2);
  });
  EXPECT_NE(what.find("x.yaml: limits: must be a number or a list of 2 numbers"), std::string::npos)
      << what;
}

}  // namespace
}  // namespace tsmh::config
