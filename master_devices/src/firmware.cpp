#include "master_devices/firmware.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace tsmh::master_devices {

FirmwareConfig default_console_firmware() {
  FirmwareConfig c;
  c.info.firmware_version = 0x0100;
  c.info.serial_number = 0x00C0FFEE;
  c.info.dof = 2;
  c.info.nominal_rate_hz = 1000;
  // 4096-line quadrature encoder (16384 counts/rev) behind a 2.5:1 capstan.
  c.info.counts_per_rev = {40960, 40960};
  c.info.max_current_ma = {4000, 4000};
  c.info.default_watchdog_ms = 50;
  c.encoder_offset_counts = {0, 0};
  c.mount_direction = {1, 1};
  return c;
}

Firmware::Firmware(const FirmwareConfig& config) : config_(config) {
  calibration_.watchdog_ms = config_.info.default_watchdog_ms;
  for (std::size_t j = 0; j < protocol::kJoints; ++j) {
    calibration_.current_limit_ma[j] = config_.info.max_current_ma[j];
    calibration_.direction[j] = 1;
  }
}

bool Firmware::motors_on() const {
  return enable_ && fault_ == protocol::FirmwareFault::kNone && !watchdog_tripped_ &&
         !buttons_.e_stop;
}

double Firmware::applied_torque_nm(std::size_t j) const {
  return config_.mount_direction[j] * applied_current_a(j) *
         config_.joints[j].torque_constant_nm_per_a;
}

void Firmware::update_applied_current() {
  current_limited_ = false;
  for (std::size_t j = 0; j < protocol::kJoints; ++j) {
    if (!motors_on() || j >= config_.info.dof) {
      applied_ma_[j] = 0.0;
      continue;
    }
    const double limit =
        std::min<double>(calibration_.current_limit_ma[j], config_.info.max_current_ma[j]);
    const double cmd = commanded_ma_[j];
    applied_ma_[j] = std::clamp(cmd, -limit, limit);
    if (applied_ma_[j] != cmd) current_limited_ = true;
  }
}

void Firmware::step(std::int64_t dt_ns) {
  if (dt_ns <= 0) return;
  time_ns_ += static_cast<std::uint64_t>(dt_ns);
  const std::uint64_t watchdog_ns = std::uint64_t{calibration_.watchdog_ms} * 1'000'000u;
  if (host_seen_ && !watchdog_tripped_ && time_ns_ - last_output_ns_ > watchdog_ns) {
    watchdog_tripped_ = true;
    ++stats_.watchdog_trips;
  }
  update_applied_current();

  // Semi-implicit Euler in sub-steps short enough for the hard-stop spring.
  const double dt = static_cast<double>(dt_ns) * 1e-9;
  const int substeps = std::max(1, static_cast<int>(std::ceil(dt / 1e-4)));
  const double h = dt / substeps;
  for (std::size_t j = 0; j < config_.info.dof && j < protocol::kJoints; ++j) {
    const MechanismJoint& m = config_.joints[j];
    for (int s = 0; s < substeps; ++s) {
      double tau = applied_torque_nm(j) + external_torque_[j] - m.damping_nms_per_rad * qd_[j];
      if (q_[j] > m.position_max_rad) {
        tau -= m.stop_stiffness_nm_per_rad * (q_[j] - m.position_max_rad) + 0.05 * qd_[j];
      } else if (q_[j] < m.position_min_rad) {
        tau -= m.stop_stiffness_nm_per_rad * (q_[j] - m.position_min_rad) + 0.05 * qd_[j];
      }
      qd_[j] += h * tau / m.inertia_kgm2;
      q_[j] += h * qd_[j];
    }
  }
}

std::int32_t Firmware::encoder_counts(std::size_t j) const {
  if (j >= config_.info.dof) return 0;
  const double counts_per_rad = config_.info.counts_per_rev[j] / (2.0 * std::numbers::pi);
  const double raw = config_.encoder_offset_counts[j] +
                     config_.mount_direction[j] * std::floor(q_[j] * counts_per_rad + 0.5);
  // A real 24-bit counter wraps; clamping keeps the emulator's reports valid.
  return static_cast<std::int32_t>(
      std::clamp(raw, double{protocol::kCountsMin}, double{protocol::kCountsMax}));
}

std::size_t Firmware::make_input_report(std::span<std::uint8_t> out) {
  protocol::InputReport r;
  r.sequence = input_sequence_++;
  r.device_time_us = static_cast<std::uint32_t>(time_us() & 0xFFFFFFFFu);
  for (std::size_t j = 0; j < protocol::kJoints; ++j)
    r.counts[j] = encoder_counts(j);
  r.buttons = buttons_;
  r.status.torque_enabled = motors_on();
  r.status.watchdog_tripped = watchdog_tripped_;
  r.status.fault = fault_ != protocol::FirmwareFault::kNone;
  r.status.current_limited = current_limited_;
  r.last_output_sequence = last_output_sequence_;
  r.fault = fault_;
  ++stats_.input_reports;
  return protocol::encode(r, out).value;
}

protocol::Error Firmware::on_output_report(std::span<const std::uint8_t> bytes) {
  const auto decoded = protocol::decode_output(bytes);
  if (!decoded.ok()) {
    ++stats_.output_rejected;
    return decoded.error;
  }
  const protocol::OutputReport& r = decoded.value;
  ++stats_.output_accepted;
  host_seen_ = true;
  last_output_ns_ = time_ns_;
  watchdog_tripped_ = false;
  last_output_sequence_ = r.sequence;
  if (r.clear_fault) fault_ = protocol::FirmwareFault::kNone;
  enable_ = r.enable;
  commanded_ma_ = r.current_ma;
  update_applied_current();
  return {};
}

std::size_t Firmware::get_feature(std::uint8_t report_id, std::span<std::uint8_t> out) const {
  switch (report_id) {
    case protocol::kDeviceInfoReportId:
      return protocol::encode(config_.info, out).value;
    case protocol::kCalibrationReportId:
      return protocol::encode(calibration_, out).value;
    default:
      return 0;
  }
}

protocol::Error Firmware::set_feature(std::span<const std::uint8_t> bytes) {
  if (bytes.empty() || bytes[0] != protocol::kCalibrationReportId) {
    return protocol::Error{protocol::ErrorCode::kWrongReportId, "feature", "report_id",
                           bytes.empty() ? -1 : bytes[0]};
  }
  const auto decoded = protocol::decode_calibration(bytes);
  if (!decoded.ok()) return decoded.error;
  calibration_ = decoded.value;
  ++stats_.features_set;
  update_applied_current();
  return {};
}

void Firmware::on_link_lost() {
  enable_ = false;
  commanded_ma_ = {};
  host_seen_ = false;
  update_applied_current();
}

void Firmware::inject_fault(protocol::FirmwareFault f) {
  fault_ = f;
  update_applied_current();
}

}  // namespace tsmh::master_devices
