#pragma once
// Fixed-size value types exchanged between a master device and the 1 kHz
// loop. Fixed size on purpose: the loop copies them every tick, so they must
// never allocate.

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "realtime/joints.hpp"

namespace tsmh::master_devices {

/// Upper bound on the joints of any master we drive, and one value per
/// joint (entries at and beyond the device's dof are zero): the project's
/// one joint count and joint array (realtime/joints.hpp), named for devices.
inline constexpr std::size_t kMaxDof = realtime::kMaxJoints;
using realtime::JointArray;

struct Buttons {
  bool dead_man = false;  ///< true while the operator holds the dead-man switch
  bool e_stop = false;    ///< true while the emergency stop is pressed
  bool clutch = false;    ///< true while the operator re-indexes (slave frozen)
  /// true while the operator presses the recalibration button (haptic-server
  /// starts a recalibration on the press; docs/haptic-server.md)
  bool calibrate = false;
  friend bool operator==(const Buttons&, const Buttons&) = default;
};

/// What a device can be doing. Only kOk delivers torque.
enum class DeviceStatus : std::uint8_t {
  kClosed,        ///< not opened yet, or closed
  kOk,            ///< streaming readings; torque follows write_torque() when enabled
  kDisconnected,  ///< link lost (unplugged, stale); torque is zero; recovers by itself
  kFault,         ///< latched fault; torque forced to zero until clear_fault()
};

/// Why a device is in kFault. Latched with the fault.
enum class FaultCode : std::uint8_t {
  kNone,
  kDeviceReported,  ///< the device's own status says fault (over-current, driver error)
  kWorkspace,       ///< a joint left its workspace by more than the margin (bad zero?)
  kBadReports,      ///< too many consecutive malformed reports from the device
  kHostRequested,   ///< the host called raise_fault()
  kHandshake,       ///< the device did not accept the calibration we sent
  kLinkLost,        ///< the link went away (unplugged) on a device that cannot resume by itself
  kOtherSession,    ///< a second keyed master on the link (lcm driver): the session is over
};

std::string_view to_string(DeviceStatus s);
std::string_view to_string(FaultCode f);

/// The newest sample of a device, as returned by Device::read().
struct DeviceReading {
  std::int64_t t_ns =
      0;  ///< sample time: CLOCK_MONOTONIC ns (simulated time for simulated devices)
  std::uint64_t sequence = 0;  ///< +1 per new sample from the device; 0 = no sample yet
  std::uint32_t dof = 0;
  JointArray q{};              ///< joint angle, rad (calibrated)
  JointArray qd{};             ///< joint velocity, rad/s
  JointArray tau_commanded{};  ///< torque the driver last sent to the device after limits, N m
  Buttons buttons;
  DeviceStatus status = DeviceStatus::kClosed;
  FaultCode fault = FaultCode::kNone;
  bool enabled = false;  ///< torque output enabled (host request, and the device agrees)
  bool fresh = false;    ///< a new sample arrived since the previous read()
  /// kDisconnected only because the newest sample is older than the device's
  /// freshness bound while its link is up (a silent or late device, or the
  /// first cycles of an unplug before the link-loss path fires). Torque is
  /// zero as for any kDisconnected; unlike a lost link it ends by itself, with
  /// torque still enabled, as soon as fresh samples arrive. A loop may treat
  /// it more leniently than a lost link (e.g. not latch its own fault).
  bool stale = false;
};

/// What a device can do, CHAI3D-style. Filled from the device profile / settings.
struct DeviceSpec {
  std::string model;   ///< e.g. "tsm-console-2dof"
  std::string driver;  ///< registry name of the driver, e.g. "hid"
  std::uint32_t dof = 0;
  std::array<std::string, kMaxDof> joint_names{};
  JointArray max_continuous_torque_nm{};  ///< sustainable torque per joint
  JointArray peak_torque_nm{};            ///< short-term torque per joint (commands clamp here)
  JointArray encoder_resolution_rad{};    ///< one encoder count, rad (0 for continuous sim)
  JointArray position_min_rad{};          ///< workspace per joint
  JointArray position_max_rad{};
  JointArray max_stiffness_nm_per_rad{};  ///< highest stable rendered stiffness at the nominal rate
                                          ///< (0 = unknown)
  double nominal_rate_hz = 0.0;           ///< rate at which the device produces samples
  /// The operator can press a recalibrate button (Buttons::calibrate) on it.
  bool has_calibrate_button = false;
};

/// The rules every driver applies to a reading before the loop sees it: with
/// no sample yet, or the newest older than `fresh_bound_ns`, an OK device
/// reads as kDisconnected with `stale` set (torque zero; OK again with the
/// next fresh sample, nothing to reconnect); whenever the device is not OK,
/// torque output reads as disabled with nothing commanded.
constexpr void apply_reading_rules(DeviceReading& r, std::int64_t now_ns,
                                   std::int64_t fresh_bound_ns, bool enable_requested) noexcept {
  if (r.status == DeviceStatus::kOk && (r.sequence == 0 || now_ns - r.t_ns > fresh_bound_ns)) {
    r.status = DeviceStatus::kDisconnected;
    r.stale = true;
  }
  if (r.status != DeviceStatus::kOk) {
    r.enabled = false;
    r.tau_commanded = {};
  } else {
    r.enabled = r.enabled && enable_requested;
  }
}

}  // namespace tsmh::master_devices
