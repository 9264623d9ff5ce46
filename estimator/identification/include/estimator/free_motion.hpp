#pragma once
// Free-motion identification: a robot in surgery has no tip
// sensor, so `tsm fit --free-motion` and `tsm gap --free-motion` identify the
// friction from data recorded while the instrument moves in free space. There
// the distal torque is only the joint's own inertia and damping torque,
// J xdd_out + b xd_out, computed from the joint encoder x_out when it exists
// and J, b are given; otherwise it is taken as zero (and the notes say so).
//
// Data that shows contact is refused (estimator/contact_check.hpp;
// docs/identification.md, "Free-motion identification").

#include <optional>
#include <string>
#include <vector>

#include "estimator/contact_check.hpp"
#include "estimator/recording.hpp"

namespace tsmh::estimator {

struct FreeMotionConfig {
  /// Joint-side (output pulley + instrument) inertia, kg m^2, and viscous
  /// damping, N m s/rad. Used only with a joint encoder (x_out); absent:
  /// the distal torque is taken as zero.
  std::optional<double> joint_inertia;
  std::optional<double> joint_damping;
  ContactCheckConfig contact;
};

struct FreeMotionData {
  /// The input with tau_out replaced by the free joint's distal torque.
  Recording recording;
  /// "inertia_damping" (J xdd_out + b xd_out) or "zero".
  std::string distal_source;
  double distal_rms_nm = 0.0;  ///< rms of that distal torque
  ContactCheck contact;
  std::vector<std::string> notes;  ///< for the report and stderr
};

/// Checks that `rec` shows free motion and builds the recording the fit and
/// the gap workflow consume. Throws DataError (file, column, what and where)
/// when tau_in or the radius is missing, x_out is partly non-finite, J or b
/// is negative or non-finite, there is too little sliding to judge, or the
/// data shows contact. A tau_out column in `rec` is ignored (a note says so).
FreeMotionData free_motion_recording(const Recording& rec, const FreeMotionConfig& config = {});

}  // namespace tsmh::estimator
