#pragma once
// Device profiles: what the host must know about one model of console to turn
// encoder counts into radians and torques into motor currents, and which
// limits it must never exceed. Loaded from YAML (master_devices/profiles/);
// every validation error names the file and the field.

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "config/field_reader.hpp"
#include "master_devices/types.hpp"

namespace tsmh::master_devices {

struct JointProfile {
  std::string name;
  double counts_per_rad = 0.0;  ///< encoder counts per joint radian, > 0
  int direction = 1;  ///< +1 or -1: joint frame = direction x device frame (angle and torque)
  std::int32_t zero_offset_counts = 0;      ///< raw count at the joint's zero
  double torque_constant_nm_per_a = 0.0;    ///< joint torque per motor ampere, > 0
  double current_limit_continuous_a = 0.0;  ///< > 0
  double current_limit_peak_a = 0.0;        ///< >= continuous
  double position_min_rad = 0.0;            ///< workspace, min < max
  double position_max_rad = 0.0;
  double max_stiffness_nm_per_rad = 0.0;  ///< stable rendered stiffness (0 = unknown)
};

struct DeviceProfile {
  std::string name;         ///< model id, e.g. "tsm-console-2dof"
  std::string description;  ///< human-readable
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  double nominal_rate_hz = 0.0;
  std::uint16_t watchdog_ms = 50;        ///< programmed into the firmware at open
  double thermal_time_constant_s = 2.0;  ///< I^2 t window for the continuous current limit
  std::vector<JointProfile> joints;      ///< 1 .. kMaxDof
  std::string source;                    ///< where it was loaded from
};

/// Validates and converts a profile document; `source` names it in errors.
DeviceProfile parse_profile(const YAML::Node& root, const std::string& source);
/// Reads and parses a profile file. Throws config::ConfigError.
DeviceProfile load_profile(const std::filesystem::path& path);
/// All *.yaml profiles in a directory, sorted by file name. Throws config::ConfigError.
std::vector<DeviceProfile> load_profiles(const std::filesystem::path& dir);

/// Our two-DOF console's profile (the same as profiles/tsm-console-2dof.yaml).
DeviceProfile builtin_console_profile();

/// The spec a device with this profile offers.
DeviceSpec spec_from_profile(const DeviceProfile& p, const std::string& driver);

/// "1209:0001" for messages and listings.
std::string usb_id_string(std::uint16_t vendor_id, std::uint16_t product_id);

}  // namespace tsmh::master_devices
