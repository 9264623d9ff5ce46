#pragma once
// A master's own description for the mapping layer (axis_mapping.hpp): its
// kinematics, its handle's workspace and force limits in its own units, its
// joints' torque limits, its update rate and its buttons by name. Loaded from
// YAML (master_devices/profiles/masters/*.yaml; docs/master-devices.md,
// "Masters of any shape").

#include <filesystem>
#include <string>

#include "config/field_reader.hpp"
#include "master_devices/kinematics.hpp"

namespace tsmh::master_devices {

struct MasterProfile {
  std::string name;
  std::string description;
  KinematicsSpec kinematics;
  /// Names of the task axes (x, y, z; or the joint names for identity).
  std::array<std::string, kMaxDof> axis_names{};
  /// Per task axis, in the device's units (m or rad): the handle's workspace.
  JointArray workspace_min{}, workspace_max{};
  /// Per task axis, in the device's units (N or N m): |force| never above.
  JointArray force_limit{};
  /// Per device joint, N m: |torque| never above (ignored for identity
  /// kinematics, where it equals force_limit).
  JointArray joint_torque_limit_nm{};
  double update_rate_hz = 0.0;
  /// Button names in bit order: bit b of the device's raw button word is
  /// button_names[b].
  std::array<std::string, 32> button_names{};
  std::size_t buttons = 0;

  std::size_t task_axes() const { return kinematics.task_axes(); }
  /// Index of the task axis called `name`, or -1.
  int axis_index(std::string_view name) const;
  /// Bit of the button called `name`, or -1.
  int button_bit(std::string_view name) const;
};

/// Parses a master profile; every error names the file, the field and the line.
MasterProfile parse_master_profile(const std::string& yaml_text, const std::string& origin);
MasterProfile load_master_profile(const std::filesystem::path& path);

}  // namespace tsmh::master_devices
