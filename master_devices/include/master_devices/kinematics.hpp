#pragma once
// A master's kinematics: from the joint angles its driver reads to the
// coordinates of its handle (the "task" axes), and the Jacobian that takes a
// force on those axes back to joint torques (tau = J^T f). Fixed-size, no
// allocation: called every tick by the mapping layer (axis_mapping.hpp).

#include <cstddef>
#include <string>

#include "master_devices/types.hpp"

namespace tsmh::master_devices {

/// J[k][j] = d task_k / d q_j.
using Jacobian = std::array<JointArray, kMaxDof>;

enum class KinematicsType {
  kIdentity,    ///< the task axes are the joints (a serial console, or a device whose
                ///< SDK reports its handle's Cartesian position and takes Cartesian forces)
  kPantograph,  ///< planar five-bar: two base joints -> handle (x, y) in m
};

/// Planar five-bar (pantograph) geometry. Base joints at (0, 0) and (d, 0);
/// joint angles from the +x axis, counter-clockwise; proximal links of length
/// `l`, distal links of length `L` meeting at the handle, which sits on the
/// +y side of the line through the two elbows.
struct PantographGeometry {
  double l_m = 0.0;  ///< proximal (motor-side) link length
  double L_m = 0.0;  ///< distal link length
  double d_m = 0.0;  ///< distance between the two base joints
};

struct KinematicsSpec {
  KinematicsType type = KinematicsType::kIdentity;
  std::size_t joints = 0;  ///< joint count of the device
  PantographGeometry pantograph;
  /// Task axes: `joints` for identity, 2 for the pantograph.
  std::size_t task_axes() const { return type == KinematicsType::kPantograph ? 2 : joints; }
};

/// Forward kinematics and Jacobian at q. Returns false (x and J untouched)
/// where the kinematics has no solution or is singular (a pantograph whose
/// elbows are further apart than 2 L, or whose links are aligned): the caller
/// then renders no force.
bool forward_kinematics(const KinematicsSpec& k, const JointArray& q, JointArray& x, Jacobian& J);

/// "identity" / "pantograph".
std::string_view to_string(KinematicsType t);

}  // namespace tsmh::master_devices
