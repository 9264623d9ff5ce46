#pragma once
// Fixed-size, trivially copyable snapshots of the five messages the bridge
// carries (MASTER_STATE and MASTER_FORCE are the lcm device driver's, which
// decodes and checks them itself: master_devices/lcm_device.hpp). The loop and
// the transport threads exchange these (realtime::LatestValue, SpscQueue)
// instead of the generated LCM classes, whose std::vector fields would allocate. Field names
// follow lcmtypes/*.lcm; the first num_joints entries of each array are valid.

#include <array>
#include <cstdint>

#include "realtime/joints.hpp"

namespace tsmh::bridge {

/// Joints per message this build handles (a message with more is rejected:
/// joint count) and the per-joint array: the project's one joint count
/// (realtime/joints.hpp).
using realtime::JointArray;
using realtime::kMaxJoints;

// Common header of every sample:
//   utime      sender's CLOCK_MONOTONIC, microseconds (from the message)
//   seq        sender's sequence number, +1 per message (from the message)
//   receive_ns receiver's CLOCK_MONOTONIC when the message was taken off the
//              socket, nanoseconds (0 in samples that are being sent)
//   num_joints valid entries in the joint arrays (1..kMaxJoints)

struct SlaveStateSample {
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  std::int64_t receive_ns = 0;
  std::int32_t num_joints = 0;
  std::int32_t status = 0;  ///< bit 0 controller enabled, 1 holding, 2 fault
  JointArray x_in{};        ///< motor-side input pulley angle, rad
  JointArray x_out{};       ///< joint angle, rad (NaN: joint has no encoder)
  JointArray T1{};          ///< proximal tension, tendon 1, N
  JointArray T3{};          ///< proximal tension, tendon 3, N
  JointArray radius_m{};    ///< pulley radius, m
};

struct SlaveTruthSample {
  std::int64_t utime = 0;
  std::int64_t seq = 0;  ///< equals the seq of the SLAVE_STATE of the same tick
  std::int64_t receive_ns = 0;
  std::int32_t num_joints = 0;
  JointArray tau_out{};        ///< true distal torque, N m
  JointArray friction{};       ///< true total sheath friction, N
  JointArray tau_in{};         ///< true proximal torque, N m
  JointArray x_out{};          ///< true joint angle, rad
  JointArray contact_force{};  ///< tissue contact force, N
  JointArray indentation{};    ///< tissue indentation, m
};

struct MasterCommandSample {
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  std::int64_t receive_ns = 0;
  std::int32_t num_joints = 0;
  bool enable = false;        ///< false: slave holds position, motors safe
  bool clutch = false;        ///< operator re-indexing: reference frozen
  JointArray position_ref{};  ///< slave joint position reference, rad
};

/// CALIBRATION_REQUEST: recalibrate the joints marked.
struct CalibrationRequestSample {
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  std::int64_t receive_ns = 0;
  std::int32_t num_joints = 0;
  std::array<bool, kMaxJoints> recalibrate{};
};

struct HapticStatusSample {
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  std::int64_t receive_ns = 0;
  std::int32_t num_joints = 0;
  std::int32_t state = 0;            ///< 0 DISABLED, 1 ENABLED, 2 FAULT
  std::int32_t feedback_source = 0;  ///< 0 estimated, 1 naive, 2 none
  /// bit 0 stale fade, 1 e-stop, 2 dead-man released, 3 saturated, 4 rate
  /// limited, 5 estimate lost, 6 slave clock jumped, 7 deadline missed,
  /// 12 oscillation detected, 13 passivity controller active
  /// 8 drift suspected, 9 recalibration running
  std::int32_t flags = 0;
  double rate_hz = 0;
  double lateness_p50_us = 0;
  double lateness_p99_us = 0;
  double lateness_max_us = 0;
  double compute_p99_us = 0;
  std::int64_t overruns = 0;
  double slave_age_ms = 0;
  std::int64_t slave_rejected = 0;
  std::int64_t slave_seq_gaps = 0;
  double slave_latency_p99_us = 0;
  JointArray tau_in{};
  JointArray tau_out_est{};
  JointArray friction_est{};
  JointArray torque_cmd{};
  JointArray master_q{};
  std::int64_t oscillation_trips = 0;  ///< sustained oscillations detected since start
  JointArray oscillation_rms{};        ///< band RMS of the rendered torque, N m
  JointArray passivity_energy{};       ///< master-side observed energy W_M, J
  JointArray passivity_dissipated{};   ///< removed by the passivity controller, J

  // Drift alarm and recalibration.
  std::int32_t calibration_state = 0;   ///< haptics::CalibrationState
  std::int32_t calibration_reason = 0;  ///< haptics::CalibrationReason
  std::int32_t calibration_joint = -1;
  JointArray friction_scale{};
  JointArray drift_scale{};
};

/// How long ago the sample was received, by the receiver's clock (always valid).
template <class Sample>
constexpr std::int64_t receive_age_ns(const Sample& s, std::int64_t now_ns) noexcept {
  return now_ns - s.receive_ns;
}

/// How long ago the sender took the sample: valid only when sender and
/// receiver share CLOCK_MONOTONIC (same host).
template <class Sample>
constexpr std::int64_t sample_age_ns(const Sample& s, std::int64_t now_ns) noexcept {
  return now_ns - s.utime * 1000;
}

}  // namespace tsmh::bridge
