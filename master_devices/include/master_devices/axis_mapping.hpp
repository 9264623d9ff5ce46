#pragma once
// The mapping layer between a master of any shape and the slave's joints.
// The master's own coordinates are its handle's task axes (MasterProfile:
// joints, or a Cartesian handle through its kinematics); each slave joint i
// follows one task axis k:
//
//   v_i = scale_i * x_k + offset_i        (rad; clutch re-indexes offset_i)
//
// and the slave joint's torque goes back by virtual work, then through the
// Jacobian transpose:
//
//   f_k = sum over i on axis k of scale_i * tau_i     (N or N m on the handle)
//   tau_q = J(q)^T f                                   (N m at the device's joints)
//
// each clamped to the profile's limits in the device's own units (the whole
// vector scaled down, so the force keeps its direction). Buttons are mapped
// by name. Every call after construction is allocation-free (1 kHz loop).

#include <cstdint>

#include "master_devices/master_profile.hpp"

namespace tsmh::master_devices {

struct AxisMapConfig {
  int master_axis = -1;  ///< task axis index in the profile
  double scale = 1.0;    ///< slave rad per device unit (m or rad); negative flips the sign
  double offset = 0.0;   ///< v_i at the workspace's centre, rad
};

/// Which button (bit in the raw word) does what; -1: none. `dead_man_held`:
/// the device has no dead-man switch and the setup accepts that (the server's
/// e-stop and the watchdogs still apply).
struct ButtonRoles {
  int dead_man = -1, e_stop = -1, clutch = -1, calibrate = -1;
  bool dead_man_held = false;
};

struct MappingConfig {
  std::size_t slave_joints = 0;
  std::array<AxisMapConfig, kMaxDof> axes{};
  ButtonRoles buttons;
};

/// Reads a `mapping:` section: `joints:` one entry per slave joint
/// ({axis: NAME, scale: S, offset: O}), `buttons:` {dead_man: NAME | held,
/// e_stop: NAME, clutch: NAME, calibrate: NAME}. Names are the profile's;
/// an unknown one is an error naming the field and listing the known ones.
MappingConfig parse_mapping(const YAML::Node& node, const MasterProfile& profile,
                            const std::string& origin, const std::string& path);

class MasterMapping {
 public:
  MasterMapping(const MasterProfile& profile, const MappingConfig& config);

  /// Every tick with the device's joint angles and raw button word. False
  /// (position held, no force) where the kinematics has no solution.
  bool update(const JointArray& q, std::uint32_t raw_buttons);

  std::size_t slave_joints() const { return config_.slave_joints; }
  /// v: the slave joint positions the master asks for, rad.
  const JointArray& slave_position() const { return v_; }
  /// The handle's task coordinates (device units), clamped to the workspace.
  const JointArray& handle() const { return x_; }
  Buttons buttons() const { return buttons_; }
  bool valid() const { return valid_; }

  /// Slave joint torques (N m) -> the handle's force in device units, within
  /// the profile's force_limit. Zero for a non-finite input or an invalid pose.
  JointArray handle_force(const JointArray& tau_slave) const;
  /// Slave joint torques -> device joint torques (N m) through J^T, within
  /// force_limit and joint_torque_limit_nm.
  JointArray joint_torques(const JointArray& tau_slave) const;

 private:
  MasterProfile profile_;
  MappingConfig config_;
  JointArray offset_{};
  JointArray x_{}, v_{};
  Jacobian J_{};
  Buttons buttons_;
  bool valid_ = false;
  bool clutched_ = false;
};

}  // namespace tsmh::master_devices
