#pragma once
// The console protocol (docs/hid-protocol.md), version 1: one codec shared by
// the `hid` driver, the `usb` driver and the device-side emulator.
//
// Every report starts with its report-ID byte and ends with a CRC-16 (the
// USB link has its own CRC; ours catches garbage that the link delivered
// faithfully: firmware or host memory bugs, a different device answering on
// the same VID/PID). Encoders and decoders are pure functions; decoders
// validate everything (length, ID, CRC, version, reserved bits, value ranges)
// and return an error value, never crash, never allocate.

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "master_devices/types.hpp"

namespace tsmh::master_devices::protocol {

inline constexpr std::uint8_t kVersion = 1;
inline constexpr std::size_t kJoints = 2;  ///< joint slots in every report

inline constexpr std::uint8_t kInputReportId = 0x01;
inline constexpr std::uint8_t kOutputReportId = 0x02;
inline constexpr std::uint8_t kDeviceInfoReportId = 0x03;
inline constexpr std::uint8_t kCalibrationReportId = 0x04;

/// Sizes including the report-ID byte (what hidapi reads/writes).
inline constexpr std::size_t kInputReportSize = 24;
inline constexpr std::size_t kOutputReportSize = 12;
inline constexpr std::size_t kDeviceInfoReportSize = 32;
inline constexpr std::size_t kCalibrationReportSize = 24;
inline constexpr std::size_t kMaxReportSize = 32;

/// Encoder counts are 24-bit signed values carried in int32 fields.
inline constexpr std::int32_t kCountsMin = -(1 << 23);
inline constexpr std::int32_t kCountsMax = (1 << 23) - 1;
/// Motor current commands and limits, mA.
inline constexpr std::int32_t kMaxCurrentMa = 10000;
inline constexpr std::uint16_t kWatchdogMinMs = 1;
inline constexpr std::uint16_t kWatchdogMaxMs = 1000;

/// What the firmware says is wrong when it reports a fault.
enum class FirmwareFault : std::uint8_t {
  kNone = 0,
  kOverCurrent = 1,
  kOverTemperature = 2,
  kEncoder = 3,
  kSupply = 4,
};
inline constexpr std::uint8_t kFirmwareFaultMax = 4;

struct StatusFlags {
  bool torque_enabled = false;    ///< the firmware drives the motors
  bool watchdog_tripped = false;  ///< no valid output report within the watchdog time: torque zero
  bool fault = false;             ///< latched firmware fault: torque zero until clear_fault
  bool current_limited = false;   ///< the last command was clamped to the current limit
  friend bool operator==(const StatusFlags&, const StatusFlags&) = default;
};

/// Device -> host, interrupt IN, every device period.
struct InputReport {
  std::uint16_t sequence = 0;        ///< +1 per report, wraps
  std::uint32_t device_time_us = 0;  ///< firmware clock, wraps every ~71 min
  std::array<std::int32_t, kJoints> counts{};
  Buttons buttons;
  StatusFlags status;
  std::uint16_t last_output_sequence = 0;      ///< sequence of the newest accepted output report
  FirmwareFault fault = FirmwareFault::kNone;  ///< non-zero exactly when status.fault
  friend bool operator==(const InputReport&, const InputReport&) = default;
};

/// Host -> device, interrupt OUT (or SET_REPORT), once per host period.
struct OutputReport {
  std::uint16_t sequence = 0;
  bool enable = false;                             ///< drive the motors with current_ma
  bool clear_fault = false;                        ///< request to clear a latched firmware fault
  std::array<std::int16_t, kJoints> current_ma{};  ///< motor current, mA, |x| <= kMaxCurrentMa
  friend bool operator==(const OutputReport&, const OutputReport&) = default;
};

/// Feature report, GET only: what the device is.
struct DeviceInfo {
  std::uint16_t firmware_version = 0;  ///< major << 8 | minor
  std::uint32_t serial_number = 0;
  std::uint8_t dof = 0;                                 ///< 1 .. kJoints
  std::uint16_t nominal_rate_hz = 0;                    ///< input reports per second, > 0
  std::array<std::uint32_t, kJoints> counts_per_rev{};  ///< > 0 for joints < dof, else 0
  std::array<std::uint16_t, kJoints> max_current_ma{};  ///< hardware limit, <= kMaxCurrentMa
  std::uint16_t default_watchdog_ms = 0;
  friend bool operator==(const DeviceInfo&, const DeviceInfo&) = default;
};

/// Feature report, GET and SET: what the host configures. The firmware
/// applies current limits and the watchdog; it stores zero offsets and
/// directions (for tools) but reports raw counts.
struct Calibration {
  std::uint16_t watchdog_ms = 0;  ///< kWatchdogMinMs .. kWatchdogMaxMs
  std::array<std::int32_t, kJoints> zero_offset_counts{};
  std::array<std::uint16_t, kJoints> current_limit_ma{};
  std::array<std::int8_t, kJoints> direction{};  ///< +1 or -1
  friend bool operator==(const Calibration&, const Calibration&) = default;
};

enum class ErrorCode : std::uint8_t {
  kOk,
  kBufferTooSmall,      ///< encoder: output buffer shorter than the report
  kWrongLength,         ///< decoder: not exactly the report's size (short or long)
  kWrongReportId,       ///< first byte is not this report's ID
  kBadChecksum,         ///< CRC-16 mismatch: garbage
  kUnsupportedVersion,  ///< protocol version byte is not kVersion
  kReservedNotZero,     ///< a reserved bit or byte is set
  kOutOfRange,          ///< a field's value is outside its valid range
};

/// A codec error: what went wrong, in which field, with the offending value.
struct Error {
  ErrorCode code = ErrorCode::kOk;
  const char* report = "";  ///< "input", "output", "device info", "calibration"
  const char* field = "";   ///< e.g. "counts[1]"; "" when about the whole report
  std::int64_t value = 0;   ///< the offending value (length, ID, field value)
  explicit operator bool() const { return code != ErrorCode::kOk; }
};

/// "input report: counts[1]: out of range (value 8388608)". Allocates; not for the RT path.
std::string describe(const Error& e);
/// The same into a fixed buffer (no allocation); returns `buf`.
const char* describe(const Error& e, std::span<char> buf);

/// Either a value or an Error.
template <class T>
struct Result {
  T value{};
  Error error{};
  bool ok() const { return !error; }
};

/// CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final xor).
std::uint16_t crc16(std::span<const std::uint8_t> bytes);

// Encoders validate the value (a firmware or host bug must not reach the
// wire) and return the number of bytes written.
Result<std::size_t> encode(const InputReport& r, std::span<std::uint8_t> out);
Result<std::size_t> encode(const OutputReport& r, std::span<std::uint8_t> out);
Result<std::size_t> encode(const DeviceInfo& r, std::span<std::uint8_t> out);
Result<std::size_t> encode(const Calibration& r, std::span<std::uint8_t> out);

Result<InputReport> decode_input(std::span<const std::uint8_t> bytes);
Result<OutputReport> decode_output(std::span<const std::uint8_t> bytes);
Result<DeviceInfo> decode_device_info(std::span<const std::uint8_t> bytes);
Result<Calibration> decode_calibration(std::span<const std::uint8_t> bytes);

/// The HID report descriptor of the console (docs/hid-protocol.md): vendor
/// usage page 0xFF00, four numbered reports of opaque bytes.
std::span<const std::uint8_t> hid_report_descriptor();

/// Unsigned distance from `older` to `newer` for wrapping 16-bit sequences.
inline std::uint16_t sequence_delta(std::uint16_t older, std::uint16_t newer) {
  return static_cast<std::uint16_t>(newer - older);
}

}  // namespace tsmh::master_devices::protocol
