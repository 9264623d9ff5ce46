#include "master_devices/profile.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace tsmh::master_devices {
namespace {

JointProfile parse_joint(config::FieldReader& r) {
  JointProfile j;
  j.name = r.get_string("name", "");
  j.counts_per_rad = r.get_double("counts_per_rad");
  if (!(j.counts_per_rad > 0.0)) r.fail("counts_per_rad", "must be > 0");
  const long long dir = r.get_int("direction", 1);
  if (dir != 1 && dir != -1) r.fail("direction", "must be 1 or -1");
  j.direction = static_cast<int>(dir);
  const long long zero = r.get_int("zero_offset_counts", 0);
  if (zero < -(1LL << 31) || zero >= (1LL << 31))
    r.fail("zero_offset_counts", "must fit in 32 bits");
  j.zero_offset_counts = static_cast<std::int32_t>(zero);
  j.torque_constant_nm_per_a = r.get_double("torque_constant_nm_per_a");
  if (!(j.torque_constant_nm_per_a > 0.0)) r.fail("torque_constant_nm_per_a", "must be > 0");
  j.current_limit_continuous_a = r.get_double("current_limit_continuous_a");
  if (!(j.current_limit_continuous_a > 0.0)) r.fail("current_limit_continuous_a", "must be > 0");
  j.current_limit_peak_a = r.get_double("current_limit_peak_a");
  if (!(j.current_limit_peak_a >= j.current_limit_continuous_a)) {
    r.fail("current_limit_peak_a", "must be >= current_limit_continuous_a");
  }
  if (j.current_limit_peak_a > 10.0) {
    r.fail("current_limit_peak_a", "must be <= 10 A (the protocol's current range)");
  }
  j.position_min_rad = r.get_double("position_min_rad");
  j.position_max_rad = r.get_double("position_max_rad");
  if (!(j.position_min_rad < j.position_max_rad)) {
    r.fail("position_max_rad", "must be > position_min_rad");
  }
  j.max_stiffness_nm_per_rad = r.get_double("max_stiffness_nm_per_rad", 0.0);
  if (j.max_stiffness_nm_per_rad < 0.0) r.fail("max_stiffness_nm_per_rad", "must be >= 0");
  r.reject_unknown();
  return j;
}

std::uint16_t parse_usb_id(config::FieldReader& r, std::string_view key) {
  const long long v = r.get_int(key);
  if (v < 0 || v > 0xFFFF) r.fail(key, "must be a 16-bit USB ID (0 .. 0xffff)");
  return static_cast<std::uint16_t>(v);
}

}  // namespace

DeviceProfile parse_profile(const YAML::Node& root, const std::string& source) {
  if (!root.IsMap()) config::config_fail(source, "", "a profile must be a YAML map", root);
  config::FieldReader r(root, source, "");
  DeviceProfile p;
  p.source = source;
  p.name = r.get_string("name");
  if (p.name.empty()) r.fail("name", "must not be empty");
  p.description = r.get_string("description", "");
  p.vendor_id = parse_usb_id(r, "vendor_id");
  p.product_id = parse_usb_id(r, "product_id");
  p.nominal_rate_hz = r.get_double("nominal_rate_hz");
  if (!(p.nominal_rate_hz > 0.0)) r.fail("nominal_rate_hz", "must be > 0");
  const long long wd = r.get_int("watchdog_ms", 50);
  if (wd < 1 || wd > 1000) r.fail("watchdog_ms", "must be 1 .. 1000");
  p.watchdog_ms = static_cast<std::uint16_t>(wd);
  p.thermal_time_constant_s = r.get_double("thermal_time_constant_s", 2.0);
  if (!(p.thermal_time_constant_s > 0.0)) r.fail("thermal_time_constant_s", "must be > 0");

  const YAML::Node joints = r.node("joints");
  if (!joints.IsDefined()) r.fail("joints", "missing (required)");
  if (!joints.IsSequence() || joints.size() == 0) r.fail("joints", "must be a non-empty list");
  if (joints.size() > kMaxDof) {
    r.fail("joints", "at most " + std::to_string(kMaxDof) + " joints are supported");
  }
  for (std::size_t i = 0; i < joints.size(); ++i) {
    config::FieldReader jr(joints[i], source, r.element("joints", i));
    p.joints.push_back(parse_joint(jr));
  }
  r.reject_unknown();
  return p;
}

DeviceProfile load_profile(const std::filesystem::path& path) {
  return parse_profile(config::load_yaml_file(path, "profile"), path.string());
}

std::vector<DeviceProfile> load_profiles(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) {
    throw config::ConfigError(dir.string() + ": profile directory does not exist");
  }
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.is_regular_file() && entry.path().extension() == ".yaml")
      files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::vector<DeviceProfile> out;
  for (const auto& f : files)
    out.push_back(load_profile(f));
  return out;
}

DeviceProfile builtin_console_profile() {
  DeviceProfile p;
  p.name = "tsm-console-2dof";
  p.description = "tsm-haptics two-DOF console (protocol v1)";
  p.vendor_id = 0x1209;
  p.product_id = 0x0001;
  p.nominal_rate_hz = 1000.0;
  p.watchdog_ms = 50;
  p.thermal_time_constant_s = 2.0;
  p.source = "builtin";
  const char* names[] = {"pitch", "yaw"};
  for (const char* name : names) {
    JointProfile j;
    j.name = name;
    j.counts_per_rad = 40960.0 / (2.0 * std::numbers::pi);
    j.direction = 1;
    j.zero_offset_counts = 0;
    j.torque_constant_nm_per_a = 0.1;
    j.current_limit_continuous_a = 1.5;
    j.current_limit_peak_a = 3.0;
    j.position_min_rad = -1.0;
    j.position_max_rad = 1.0;
    j.max_stiffness_nm_per_rad = 5.0;
    p.joints.push_back(j);
  }
  return p;
}

DeviceSpec spec_from_profile(const DeviceProfile& p, const std::string& driver) {
  DeviceSpec s;
  s.model = p.name;
  s.driver = driver;
  s.dof = static_cast<std::uint32_t>(p.joints.size());
  s.nominal_rate_hz = p.nominal_rate_hz;
  for (std::size_t i = 0; i < p.joints.size(); ++i) {
    const JointProfile& j = p.joints[i];
    s.joint_names[i] = j.name;
    s.max_continuous_torque_nm[i] = j.torque_constant_nm_per_a * j.current_limit_continuous_a;
    s.peak_torque_nm[i] = j.torque_constant_nm_per_a * j.current_limit_peak_a;
    s.encoder_resolution_rad[i] = 1.0 / j.counts_per_rad;
    s.position_min_rad[i] = j.position_min_rad;
    s.position_max_rad[i] = j.position_max_rad;
    s.max_stiffness_nm_per_rad[i] = j.max_stiffness_nm_per_rad;
  }
  return s;
}

std::string usb_id_string(std::uint16_t vendor_id, std::uint16_t product_id) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%04x:%04x", vendor_id, product_id);
  return buf;
}

}  // namespace tsmh::master_devices
