// Device profiles: parsing, validation messages that name file and field.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "master_devices/profile.hpp"

namespace tsmh::master_devices {
namespace {

const char* kValid = R"(name: test-console
vendor_id: 0x1209
product_id: 0x0001
nominal_rate_hz: 1000
joints:
  - name: a
    counts_per_rad: 6518.986469
    torque_constant_nm_per_a: 0.1
    current_limit_continuous_a: 1.5
    current_limit_peak_a: 3.0
    position_min_rad: -1.0
    position_max_rad: 1.0
  - name: b
    counts_per_rad: 6518.986469
    direction: -1
    zero_offset_counts: 250
    torque_constant_nm_per_a: 0.1
    current_limit_continuous_a: 1.5
    current_limit_peak_a: 3.0
    position_min_rad: -1.0
    position_max_rad: 1.0
)";

std::string error_of(const std::string& yaml) {
  try {
    parse_profile(YAML::Load(yaml), "profile.yaml");
  } catch (const config::ConfigError& e) {
    return e.what();
  }
  return "(no error)";
}

std::string replace(std::string s, const std::string& from, const std::string& to) {
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

// Replaces the n-th (0-based) occurrence.
std::string replace_nth(std::string s, const std::string& from, const std::string& to, int n) {
  std::size_t at = s.find(from);
  for (int i = 0; i < n && at != std::string::npos; ++i)
    at = s.find(from, at + 1);
  EXPECT_NE(at, std::string::npos);
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

TEST(Profile, ParsesAValidProfile) {
  const DeviceProfile p = parse_profile(YAML::Load(kValid), "profile.yaml");
  EXPECT_EQ(p.name, "test-console");
  EXPECT_EQ(p.vendor_id, 0x1209);
  EXPECT_EQ(p.product_id, 0x0001);
  ASSERT_EQ(p.joints.size(), 2u);
  EXPECT_EQ(p.joints[1].direction, -1);
  EXPECT_EQ(p.joints[1].zero_offset_counts, 250);
  EXPECT_EQ(p.joints[0].direction, 1);
  EXPECT_EQ(p.watchdog_ms, 50);
}

TEST(Profile, ValidationNamesFileAndField) {
  const std::string bad_cpr =
      replace_nth(kValid, "counts_per_rad: 6518.986469", "counts_per_rad: 0", 1);
  const std::string e = error_of(bad_cpr);
  EXPECT_NE(e.find("profile.yaml: joints[1].counts_per_rad: must be > 0"), std::string::npos) << e;
  EXPECT_NE(e.find("(line 14)"), std::string::npos) << e;

  EXPECT_NE(error_of(replace(kValid, "direction: -1", "direction: 2"))
                .find("joints[1].direction: must be 1 or -1"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kValid, "vendor_id: 0x1209", "vendor_id: 0x12090"))
                .find("profile.yaml: vendor_id: must be a 16-bit USB ID"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kValid, "current_limit_peak_a: 3.0", "current_limit_peak_a: 1.0"))
                .find("joints[0].current_limit_peak_a: must be >= current_limit_continuous_a"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kValid, "position_max_rad: 1.0", "position_max_rad: -2.0"))
                .find("joints[0].position_max_rad: must be > position_min_rad"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kValid, "nominal_rate_hz: 1000", "nominal_rate_hz: fast"))
                .find("nominal_rate_hz: must be a number"),
            std::string::npos);
  EXPECT_NE(error_of(replace(kValid, "    torque_constant_nm_per_a: 0.1\n", ""))
                .find("joints[0].torque_constant_nm_per_a: missing (required)"),
            std::string::npos);
}

TEST(Profile, UnknownKeysAreErrors) {
  const std::string e = error_of(replace(kValid, "    direction: -1", "    directoin: -1"));
  EXPECT_NE(e.find("joints[1].directoin: unknown key"), std::string::npos) << e;
  EXPECT_NE(error_of(std::string(kValid) + "colour: red\n").find("colour: unknown key"),
            std::string::npos);
}

TEST(Profile, StructuralErrors) {
  EXPECT_NE(error_of("- 1\n- 2\n").find("a profile must be a YAML map"), std::string::npos);
  EXPECT_NE(error_of(replace(kValid, "joints:", "joints: 3\nx_joints:"))
                .find("joints: must be a non-empty list"),
            std::string::npos);
}

TEST(Profile, LoadProfileNamesTheFile) {
  try {
    load_profile("/nonexistent/profile.yaml");
    FAIL();
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/profile.yaml"), std::string::npos);
  }
}

TEST(Profile, ShippedProfileEqualsTheBuiltinOne) {
  const DeviceProfile file =
      load_profile(std::string(TSMH_SOURCE_DIR) + "/master_devices/profiles/tsm-console-2dof.yaml");
  const DeviceProfile builtin = builtin_console_profile();
  EXPECT_EQ(file.name, builtin.name);
  EXPECT_EQ(file.vendor_id, builtin.vendor_id);
  EXPECT_EQ(file.product_id, builtin.product_id);
  EXPECT_EQ(file.nominal_rate_hz, builtin.nominal_rate_hz);
  EXPECT_EQ(file.watchdog_ms, builtin.watchdog_ms);
  ASSERT_EQ(file.joints.size(), builtin.joints.size());
  for (std::size_t j = 0; j < file.joints.size(); ++j) {
    const JointProfile& a = file.joints[j];
    const JointProfile& b = builtin.joints[j];
    EXPECT_EQ(a.name, b.name);
    EXPECT_NEAR(a.counts_per_rad, b.counts_per_rad, 1e-5);
    EXPECT_EQ(a.direction, b.direction);
    EXPECT_EQ(a.zero_offset_counts, b.zero_offset_counts);
    EXPECT_EQ(a.torque_constant_nm_per_a, b.torque_constant_nm_per_a);
    EXPECT_EQ(a.current_limit_continuous_a, b.current_limit_continuous_a);
    EXPECT_EQ(a.current_limit_peak_a, b.current_limit_peak_a);
    EXPECT_EQ(a.position_min_rad, b.position_min_rad);
    EXPECT_EQ(a.position_max_rad, b.position_max_rad);
    EXPECT_EQ(a.max_stiffness_nm_per_rad, b.max_stiffness_nm_per_rad);
  }
}

TEST(Profile, SpecFollowsTheProfile) {
  const DeviceSpec s = spec_from_profile(builtin_console_profile(), "hid");
  EXPECT_EQ(s.dof, 2u);
  EXPECT_EQ(s.driver, "hid");
  EXPECT_DOUBLE_EQ(s.peak_torque_nm[0], 0.3);
  EXPECT_DOUBLE_EQ(s.max_continuous_torque_nm[1], 0.15);
  EXPECT_NEAR(s.encoder_resolution_rad[0], 2 * 3.141592653589793 / 40960, 1e-12);
  EXPECT_EQ(s.position_min_rad[0], -1.0);
  EXPECT_EQ(s.nominal_rate_hz, 1000.0);
  EXPECT_EQ(s.peak_torque_nm[2], 0.0) << "entries beyond dof stay zero";
  EXPECT_EQ(usb_id_string(0x1209, 0x0001), "1209:0001");
}

}  // namespace
}  // namespace tsmh::master_devices
