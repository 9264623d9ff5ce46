#pragma once
// The console's firmware, emulated: the device side of docs/hid-protocol.md
// plus the mechanism it drives (two rotary joints with inertia, damping and
// hard stops, read by quantizing encoders). It applies current limits,
// latches faults and runs the watchdog that zeroes torque when output
// reports stop.
//
// Pure and single-threaded: it knows nothing about hidapi, libusb, threads or
// clocks. Whoever hosts it (the in-process emulator transport, or a USB
// gadget program on /dev/hidg0) calls step() with elapsed time, ships the
// bytes of make_input_report() and feeds received reports back in.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "master_devices/protocol.hpp"
#include "master_devices/types.hpp"

namespace tsmh::master_devices {

/// One emulated joint of the console mechanism.
struct MechanismJoint {
  double inertia_kgm2 = 2.0e-4;         ///< handle + rotor, reflected to the joint
  double damping_nms_per_rad = 5.0e-3;  ///< viscous friction
  double torque_constant_nm_per_a =
      0.1;                         ///< joint torque per motor ampere (true, not the profile's)
  double position_min_rad = -1.2;  ///< hard stops
  double position_max_rad = 1.2;
  double stop_stiffness_nm_per_rad = 20.0;
};

struct FirmwareConfig {
  protocol::DeviceInfo info;  ///< what the DEVICE_INFO feature report says
  /// Raw encoder count at mechanism angle 0 (what a profile's zero offset undoes).
  std::array<std::int32_t, protocol::kJoints> encoder_offset_counts{};
  /// A joint mounted reversed (-1): encoder counts and motor torque both have
  /// the opposite sign of the mechanism frame (what a profile's direction undoes).
  std::array<std::int8_t, protocol::kJoints> mount_direction{1, 1};
  std::array<MechanismJoint, protocol::kJoints> joints{};
};

/// The firmware configuration matching builtin_console_profile() (profile.hpp).
FirmwareConfig default_console_firmware();

struct FirmwareStats {
  std::uint64_t input_reports = 0;
  std::uint64_t output_accepted = 0;
  std::uint64_t output_rejected = 0;  ///< malformed output reports (ignored)
  std::uint64_t watchdog_trips = 0;
  std::uint64_t features_set = 0;
};

class Firmware {
 public:
  explicit Firmware(const FirmwareConfig& config);

  /// Advances the firmware clock, watchdog and mechanism by dt_ns (> 0).
  void step(std::int64_t dt_ns);

  /// Writes the next input report into `out` (>= kInputReportSize bytes);
  /// returns its size.
  std::size_t make_input_report(std::span<std::uint8_t> out);

  /// Handles an output report from the host. Malformed ones are ignored
  /// (counted) and do not feed the watchdog; the error says why.
  protocol::Error on_output_report(std::span<const std::uint8_t> bytes);

  /// GET_REPORT(Feature, id): writes the report into `out`; returns its size,
  /// or 0 for an unknown ID (a real device STALLs).
  std::size_t get_feature(std::uint8_t report_id, std::span<std::uint8_t> out) const;

  /// SET_REPORT(Feature): only CALIBRATION is settable. Malformed or
  /// read-only reports are rejected with the reason.
  protocol::Error set_feature(std::span<const std::uint8_t> bytes);

  /// The USB link went away (cable pulled, bus reset, suspend): motors off,
  /// enable dropped until the host enables again.
  void on_link_lost();

  // ---- the world around the firmware (tests, emulators) ----
  void set_buttons(const Buttons& b) { buttons_ = b; }
  /// Torque the operator's hand applies to joint j, N m.
  void set_external_torque(std::size_t j, double tau_nm) { external_torque_[j] = tau_nm; }
  /// Latches a firmware fault (cleared by an output report with clear_fault).
  void inject_fault(protocol::FirmwareFault f);
  void set_position(std::size_t j, double q_rad) {
    q_[j] = q_rad;
    qd_[j] = 0.0;
  }

  // ---- observation ----
  double position_rad(std::size_t j) const { return q_[j]; }
  double velocity_rad_s(std::size_t j) const { return qd_[j]; }
  double applied_current_a(std::size_t j) const { return applied_ma_[j] * 1e-3; }
  double applied_torque_nm(std::size_t j) const;
  bool torque_enabled() const { return motors_on(); }
  bool watchdog_tripped() const { return watchdog_tripped_; }
  const protocol::Calibration& calibration() const { return calibration_; }
  const FirmwareStats& stats() const { return stats_; }
  std::uint64_t time_us() const { return time_ns_ / 1000; }

 private:
  bool motors_on() const;
  void update_applied_current();
  std::int32_t encoder_counts(std::size_t j) const;

  FirmwareConfig config_;
  protocol::Calibration calibration_;
  std::uint64_t time_ns_ = 0;
  std::uint64_t last_output_ns_ = 0;
  bool host_seen_ = false;  // the watchdog arms with the first valid output report
  bool watchdog_tripped_ = false;
  bool enable_ = false;
  protocol::FirmwareFault fault_ = protocol::FirmwareFault::kNone;
  bool current_limited_ = false;
  std::uint16_t input_sequence_ = 0;
  std::uint16_t last_output_sequence_ = 0;
  std::array<std::int16_t, protocol::kJoints> commanded_ma_{};
  std::array<double, protocol::kJoints> applied_ma_{};
  std::array<double, protocol::kJoints> q_{};
  std::array<double, protocol::kJoints> qd_{};
  std::array<double, protocol::kJoints> external_torque_{};
  Buttons buttons_;
  FirmwareStats stats_;
};

}  // namespace tsmh::master_devices
