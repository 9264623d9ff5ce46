#include "master_devices/protocol.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdio>

#include "realtime/enum_names.hpp"

namespace tsmh::master_devices::protocol {
namespace {

// Little-endian field access by explicit shifts: no alignment or aliasing
// assumptions, identical on every host.
void put_u8(std::span<std::uint8_t> b, std::size_t at, std::uint8_t v) {
  b[at] = v;
}
void put_u16(std::span<std::uint8_t> b, std::size_t at, std::uint16_t v) {
  b[at] = static_cast<std::uint8_t>(v & 0xFFu);
  b[at + 1] = static_cast<std::uint8_t>(v >> 8);
}
void put_u32(std::span<std::uint8_t> b, std::size_t at, std::uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i)
    b[at + i] = static_cast<std::uint8_t>((v >> (8 * i)) & 0xFFu);
}
void put_i32(std::span<std::uint8_t> b, std::size_t at, std::int32_t v) {
  put_u32(b, at, static_cast<std::uint32_t>(v));
}
void put_i16(std::span<std::uint8_t> b, std::size_t at, std::int16_t v) {
  put_u16(b, at, static_cast<std::uint16_t>(v));
}

std::uint16_t get_u16(std::span<const std::uint8_t> b, std::size_t at) {
  return static_cast<std::uint16_t>(b[at] | (b[at + 1] << 8));
}
std::uint32_t get_u32(std::span<const std::uint8_t> b, std::size_t at) {
  std::uint32_t v = 0;
  for (std::size_t i = 0; i < 4; ++i)
    v |= static_cast<std::uint32_t>(b[at + i]) << (8 * i);
  return v;
}
std::int32_t get_i32(std::span<const std::uint8_t> b, std::size_t at) {
  return static_cast<std::int32_t>(get_u32(b, at));
}
std::int16_t get_i16(std::span<const std::uint8_t> b, std::size_t at) {
  return static_cast<std::int16_t>(get_u16(b, at));
}

Error make_error(ErrorCode code, const char* report, const char* field = "",
                 std::int64_t value = 0) {
  return Error{code, report, field, value};
}

// Field names per joint, static so errors can point at them without allocating.
constexpr const char* kCountsField[kJoints] = {"counts[0]", "counts[1]"};
constexpr const char* kCurrentField[kJoints] = {"current_ma[0]", "current_ma[1]"};
constexpr const char* kCprField[kJoints] = {"counts_per_rev[0]", "counts_per_rev[1]"};
constexpr const char* kMaxCurrentField[kJoints] = {"max_current_ma[0]", "max_current_ma[1]"};
constexpr const char* kZeroField[kJoints] = {"zero_offset_counts[0]", "zero_offset_counts[1]"};
constexpr const char* kLimitField[kJoints] = {"current_limit_ma[0]", "current_limit_ma[1]"};
constexpr const char* kDirectionField[kJoints] = {"direction[0]", "direction[1]"};

// A reserved field: `width` bytes (1, 2 or 4) at `at`, zero on the wire.
struct Reserved {
  std::size_t at, width;
};

// A report's frame, said once for its encoder and its decoder: its name in
// errors, report ID (byte 0), size (the CRC in the last two bytes), whether
// byte 1 carries the protocol version, and its reserved fields (the layout
// comment above each report).
struct Layout {
  const char* name;
  std::uint8_t id;
  std::size_t size;
  bool versioned;
  std::span<const Reserved> reserved;
};

// Length, report ID, CRC, and the protocol version where the report has it.
Error check_frame(std::span<const std::uint8_t> b, const Layout& l) {
  if (b.size() != l.size) {
    return make_error(ErrorCode::kWrongLength, l.name, "", static_cast<std::int64_t>(b.size()));
  }
  if (b[0] != l.id) return make_error(ErrorCode::kWrongReportId, l.name, "report_id", b[0]);
  const std::uint16_t stored = get_u16(b, l.size - 2);
  if (crc16(b.first(l.size - 2)) != stored) {
    return make_error(ErrorCode::kBadChecksum, l.name, "crc", stored);
  }
  if (l.versioned && b[1] != kVersion) {
    return make_error(ErrorCode::kUnsupportedVersion, l.name, "version", b[1]);
  }
  return {};
}

// The first reserved field that is not zero, in the layout's order.
Error check_reserved(std::span<const std::uint8_t> b, const Layout& l) {
  for (const Reserved& f : l.reserved) {
    const std::uint32_t v = f.width == 1   ? b[f.at]
                            : f.width == 2 ? get_u16(b, f.at)
                                           : get_u32(b, f.at);
    if (v != 0) return make_error(ErrorCode::kReservedNotZero, l.name, "reserved", v);
  }
  return {};
}

// An encoder's first check: the caller's buffer holds the report.
Error check_room(std::span<const std::uint8_t> out, const Layout& l) {
  if (out.size() < l.size) return make_error(ErrorCode::kBufferTooSmall, l.name);
  return {};
}

// The end of every encoder, and its result: the report ID, the version where
// the report has it, the reserved fields zero, the CRC over the rest.
Result<std::size_t> seal(std::span<std::uint8_t> b, const Layout& l) {
  put_u8(b, 0, l.id);
  if (l.versioned) put_u8(b, 1, kVersion);
  for (const Reserved& f : l.reserved)
    std::fill_n(b.begin() + static_cast<std::ptrdiff_t>(f.at), f.width, std::uint8_t{0});
  put_u16(b, l.size - 2, crc16(std::span<const std::uint8_t>(b.data(), l.size - 2)));
  return {l.size, {}};
}

bool counts_ok(std::int32_t c) {
  return c >= kCountsMin && c <= kCountsMax;
}
bool current_ok(std::int32_t ma) {
  return ma >= -kMaxCurrentMa && ma <= kMaxCurrentMa;
}

std::uint8_t buttons_byte(const Buttons& b) {
  return static_cast<std::uint8_t>((b.dead_man ? 1u : 0u) | (b.e_stop ? 2u : 0u) |
                                   (b.clutch ? 4u : 0u));
}
std::uint8_t status_byte(const StatusFlags& s) {
  return static_cast<std::uint8_t>((s.torque_enabled ? 1u : 0u) | (s.watchdog_tripped ? 2u : 0u) |
                                   (s.fault ? 4u : 0u) | (s.current_limited ? 8u : 0u));
}

constexpr const char* kInput = "input";
constexpr const char* kOutput = "output";
constexpr const char* kInfo = "device info";
constexpr const char* kCalib = "calibration";

constexpr Reserved kInputReserved[] = {{21, 1}};
constexpr Reserved kOutputReserved[] = {{8, 2}};
constexpr Reserved kInfoReserved[] = {{9, 1}, {26, 4}};
constexpr Reserved kCalibReserved[] = {{1, 1}, {18, 4}};
constexpr Layout kInputLayout{kInput, kInputReportId, kInputReportSize, true, kInputReserved};
constexpr Layout kOutputLayout{kOutput, kOutputReportId, kOutputReportSize, false, kOutputReserved};
constexpr Layout kInfoLayout{kInfo, kDeviceInfoReportId, kDeviceInfoReportSize, true,
                             kInfoReserved};
constexpr Layout kCalibLayout{kCalib, kCalibrationReportId, kCalibrationReportSize, false,
                              kCalibReserved};

}  // namespace

namespace {
// Table-driven CRC: one lookup per byte instead of eight shifts (the host
// decodes a report per millisecond, a firmware per report too).
constexpr std::array<std::uint16_t, 256> make_crc_table() {
  std::array<std::uint16_t, 256> table{};
  for (std::size_t i = 0; i < table.size(); ++i) {
    auto crc = static_cast<std::uint16_t>(i << 8);
    for (int bit = 0; bit < 8; ++bit) {
      crc = (crc & 0x8000u) ? static_cast<std::uint16_t>((crc << 1) ^ 0x1021u)
                            : static_cast<std::uint16_t>(crc << 1);
    }
    table[i] = crc;
  }
  return table;
}
constexpr std::array<std::uint16_t, 256> kCrcTable = make_crc_table();
}  // namespace

std::uint16_t crc16(std::span<const std::uint8_t> bytes) {
  std::uint16_t crc = 0xFFFF;
  for (std::uint8_t byte : bytes) {
    crc = static_cast<std::uint16_t>((crc << 8) ^ kCrcTable[((crc >> 8) ^ byte) & 0xFFu]);
  }
  return crc;
}

const char* describe(const Error& e, std::span<char> buf) {
  if (buf.empty()) return buf.data();
  const char* what =
      realtime::enum_name<ErrorCode::kOutOfRange>(
          e.code,
          {"ok", "buffer too small", "wrong length", "wrong report ID", "bad CRC (garbage)",
           "unsupported protocol version", "reserved bits set", "out of range"},
          "ok")
          .data();
  if (e.field[0] != '\0') {
    std::snprintf(buf.data(), buf.size(), "%s report: %s: %s (value %lld)", e.report, e.field, what,
                  static_cast<long long>(e.value));
  } else {
    std::snprintf(buf.data(), buf.size(), "%s report: %s (value %lld)", e.report, what,
                  static_cast<long long>(e.value));
  }
  return buf.data();
}

std::string describe(const Error& e) {
  std::array<char, 160> buf{};
  return std::string(describe(e, buf));
}

// ---- input report ----
// 0 id | 1 version | 2 seq u16 | 4 time_us u32 | 8 counts i32 x2 | 16 buttons
// | 17 status | 18 last_output_seq u16 | 20 fault u8 | 21 reserved | 22 crc

Result<std::size_t> encode(const InputReport& r, std::span<std::uint8_t> out) {
  if (Error e = check_room(out, kInputLayout)) return {0, e};
  for (std::size_t j = 0; j < kJoints; ++j) {
    if (!counts_ok(r.counts[j])) {
      return {0, make_error(ErrorCode::kOutOfRange, kInput, kCountsField[j], r.counts[j])};
    }
  }
  const auto fault = static_cast<std::uint8_t>(r.fault);
  if (fault > kFirmwareFaultMax || (fault != 0) != r.status.fault) {
    return {0, make_error(ErrorCode::kOutOfRange, kInput, "fault", fault)};
  }
  put_u16(out, 2, r.sequence);
  put_u32(out, 4, r.device_time_us);
  for (std::size_t j = 0; j < kJoints; ++j)
    put_i32(out, 8 + 4 * j, r.counts[j]);
  put_u8(out, 16, buttons_byte(r.buttons));
  put_u8(out, 17, status_byte(r.status));
  put_u16(out, 18, r.last_output_sequence);
  put_u8(out, 20, fault);
  return seal(out, kInputLayout);
}

Result<InputReport> decode_input(std::span<const std::uint8_t> b) {
  if (Error e = check_frame(b, kInputLayout)) return {{}, e};
  InputReport r;
  r.sequence = get_u16(b, 2);
  r.device_time_us = get_u32(b, 4);
  for (std::size_t j = 0; j < kJoints; ++j) {
    r.counts[j] = get_i32(b, 8 + 4 * j);
    if (!counts_ok(r.counts[j])) {
      return {{}, make_error(ErrorCode::kOutOfRange, kInput, kCountsField[j], r.counts[j])};
    }
  }
  const std::uint8_t buttons = b[16];
  if (buttons & 0xF8u)
    return {{}, make_error(ErrorCode::kReservedNotZero, kInput, "buttons", buttons)};
  r.buttons = Buttons{(buttons & 1u) != 0, (buttons & 2u) != 0, (buttons & 4u) != 0};
  const std::uint8_t status = b[17];
  if (status & 0xF0u)
    return {{}, make_error(ErrorCode::kReservedNotZero, kInput, "status", status)};
  r.status =
      StatusFlags{(status & 1u) != 0, (status & 2u) != 0, (status & 4u) != 0, (status & 8u) != 0};
  r.last_output_sequence = get_u16(b, 18);
  const std::uint8_t fault = b[20];
  if (fault > kFirmwareFaultMax || (fault != 0) != r.status.fault) {
    return {{}, make_error(ErrorCode::kOutOfRange, kInput, "fault", fault)};
  }
  r.fault = static_cast<FirmwareFault>(fault);
  if (Error e = check_reserved(b, kInputLayout)) return {{}, e};
  return {r, {}};
}

// ---- output report ----
// 0 id | 1 flags | 2 seq u16 | 4 current_ma i16 x2 | 8 reserved u16 | 10 crc

Result<std::size_t> encode(const OutputReport& r, std::span<std::uint8_t> out) {
  if (Error e = check_room(out, kOutputLayout)) return {0, e};
  for (std::size_t j = 0; j < kJoints; ++j) {
    if (!current_ok(r.current_ma[j])) {
      return {0, make_error(ErrorCode::kOutOfRange, kOutput, kCurrentField[j], r.current_ma[j])};
    }
  }
  put_u8(out, 1, static_cast<std::uint8_t>((r.enable ? 1u : 0u) | (r.clear_fault ? 2u : 0u)));
  put_u16(out, 2, r.sequence);
  for (std::size_t j = 0; j < kJoints; ++j)
    put_i16(out, 4 + 2 * j, r.current_ma[j]);
  return seal(out, kOutputLayout);
}

Result<OutputReport> decode_output(std::span<const std::uint8_t> b) {
  if (Error e = check_frame(b, kOutputLayout)) return {{}, e};
  OutputReport r;
  const std::uint8_t flags = b[1];
  if (flags & 0xFCu) return {{}, make_error(ErrorCode::kReservedNotZero, kOutput, "flags", flags)};
  r.enable = (flags & 1u) != 0;
  r.clear_fault = (flags & 2u) != 0;
  r.sequence = get_u16(b, 2);
  for (std::size_t j = 0; j < kJoints; ++j) {
    r.current_ma[j] = get_i16(b, 4 + 2 * j);
    if (!current_ok(r.current_ma[j])) {
      return {{}, make_error(ErrorCode::kOutOfRange, kOutput, kCurrentField[j], r.current_ma[j])};
    }
  }
  if (Error e = check_reserved(b, kOutputLayout)) return {{}, e};
  return {r, {}};
}

// ---- device info feature report ----
// 0 id | 1 version | 2 fw u16 | 4 serial u32 | 8 dof | 9 reserved | 10 rate u16
// | 12 cpr u32 x2 | 20 max_current u16 x2 | 24 watchdog u16 | 26 reserved x4 | 30 crc

namespace {
Error validate(const DeviceInfo& r) {
  if (r.dof < 1 || r.dof > kJoints) return make_error(ErrorCode::kOutOfRange, kInfo, "dof", r.dof);
  if (r.nominal_rate_hz == 0)
    return make_error(ErrorCode::kOutOfRange, kInfo, "nominal_rate_hz", 0);
  for (std::size_t j = 0; j < kJoints; ++j) {
    const bool used = j < r.dof;
    if (used ? r.counts_per_rev[j] == 0 : r.counts_per_rev[j] != 0) {
      return make_error(ErrorCode::kOutOfRange, kInfo, kCprField[j], r.counts_per_rev[j]);
    }
    if (r.max_current_ma[j] > kMaxCurrentMa || (!used && r.max_current_ma[j] != 0)) {
      return make_error(ErrorCode::kOutOfRange, kInfo, kMaxCurrentField[j], r.max_current_ma[j]);
    }
  }
  if (r.default_watchdog_ms < kWatchdogMinMs || r.default_watchdog_ms > kWatchdogMaxMs) {
    return make_error(ErrorCode::kOutOfRange, kInfo, "default_watchdog_ms", r.default_watchdog_ms);
  }
  return {};
}

Error validate(const Calibration& r) {
  if (r.watchdog_ms < kWatchdogMinMs || r.watchdog_ms > kWatchdogMaxMs) {
    return make_error(ErrorCode::kOutOfRange, kCalib, "watchdog_ms", r.watchdog_ms);
  }
  for (std::size_t j = 0; j < kJoints; ++j) {
    if (!counts_ok(r.zero_offset_counts[j])) {
      return make_error(ErrorCode::kOutOfRange, kCalib, kZeroField[j], r.zero_offset_counts[j]);
    }
    if (r.current_limit_ma[j] > kMaxCurrentMa) {
      return make_error(ErrorCode::kOutOfRange, kCalib, kLimitField[j], r.current_limit_ma[j]);
    }
    if (r.direction[j] != 1 && r.direction[j] != -1) {
      return make_error(ErrorCode::kOutOfRange, kCalib, kDirectionField[j], r.direction[j]);
    }
  }
  return {};
}

// The feature reports (device info, calibration) are checked whole, by
// validate(): before their fields are written, after they are read (and
// after the frame and the reserved fields). `write` / `read` move the fields.
template <class Report, class Write>
Result<std::size_t> encode_feature(const Report& r, std::span<std::uint8_t> out, const Layout& l,
                                   Write write) {
  if (Error e = check_room(out, l)) return {0, e};
  if (Error e = validate(r)) return {0, e};
  write(out);
  return seal(out, l);
}

template <class Report, class Read>
Result<Report> decode_feature(std::span<const std::uint8_t> b, const Layout& l, Read read) {
  if (Error e = check_frame(b, l)) return {{}, e};
  if (Error e = check_reserved(b, l)) return {{}, e};
  Report r;
  read(r);
  if (Error e = validate(r)) return {{}, e};
  return {r, {}};
}
}  // namespace

Result<std::size_t> encode(const DeviceInfo& r, std::span<std::uint8_t> out) {
  return encode_feature(r, out, kInfoLayout, [&r](std::span<std::uint8_t> o) {
    put_u16(o, 2, r.firmware_version);
    put_u32(o, 4, r.serial_number);
    put_u8(o, 8, r.dof);
    put_u16(o, 10, r.nominal_rate_hz);
    for (std::size_t j = 0; j < kJoints; ++j) {
      put_u32(o, 12 + 4 * j, r.counts_per_rev[j]);
      put_u16(o, 20 + 2 * j, r.max_current_ma[j]);
    }
    put_u16(o, 24, r.default_watchdog_ms);
  });
}

Result<DeviceInfo> decode_device_info(std::span<const std::uint8_t> b) {
  return decode_feature<DeviceInfo>(b, kInfoLayout, [b](DeviceInfo& r) {
    r.firmware_version = get_u16(b, 2);
    r.serial_number = get_u32(b, 4);
    r.dof = b[8];
    r.nominal_rate_hz = get_u16(b, 10);
    for (std::size_t j = 0; j < kJoints; ++j) {
      r.counts_per_rev[j] = get_u32(b, 12 + 4 * j);
      r.max_current_ma[j] = get_u16(b, 20 + 2 * j);
    }
    r.default_watchdog_ms = get_u16(b, 24);
  });
}

// ---- calibration feature report ----
// 0 id | 1 reserved | 2 watchdog u16 | 4 zero i32 x2 | 12 limit u16 x2
// | 16 direction i8 x2 | 18 reserved x4 | 22 crc

Result<std::size_t> encode(const Calibration& r, std::span<std::uint8_t> out) {
  return encode_feature(r, out, kCalibLayout, [&r](std::span<std::uint8_t> o) {
    put_u16(o, 2, r.watchdog_ms);
    for (std::size_t j = 0; j < kJoints; ++j) {
      put_i32(o, 4 + 4 * j, r.zero_offset_counts[j]);
      put_u16(o, 12 + 2 * j, r.current_limit_ma[j]);
      put_u8(o, 16 + j, static_cast<std::uint8_t>(r.direction[j]));
    }
  });
}

Result<Calibration> decode_calibration(std::span<const std::uint8_t> b) {
  return decode_feature<Calibration>(b, kCalibLayout, [b](Calibration& r) {
    r.watchdog_ms = get_u16(b, 2);
    for (std::size_t j = 0; j < kJoints; ++j) {
      r.zero_offset_counts[j] = get_i32(b, 4 + 4 * j);
      r.current_limit_ma[j] = get_u16(b, 12 + 2 * j);
      r.direction[j] = static_cast<std::int8_t>(b[16 + j]);
    }
  });
}

// ---- HID report descriptor ----

namespace {
// Report Count items are the report sizes without the report-ID byte.
constexpr std::array<std::uint8_t, 47> kDescriptor = {
    0x06, 0x00,
    0xFF,        // Usage Page (Vendor Defined 0xFF00)
    0x09, 0x01,  // Usage (0x01)
    0xA1, 0x01,  // Collection (Application)
    0x15, 0x00,  //   Logical Minimum (0)
    0x26, 0xFF,
    0x00,                                                         //   Logical Maximum (255)
    0x75, 0x08,                                                   //   Report Size (8)
    0x85, kInputReportId,                                         //   Report ID (1)
    0x95, static_cast<std::uint8_t>(kInputReportSize - 1),        //   Report Count (23)
    0x09, 0x01,                                                   //   Usage (0x01)
    0x81, 0x02,                                                   //   Input (Data,Var,Abs)
    0x85, kOutputReportId,                                        //   Report ID (2)
    0x95, static_cast<std::uint8_t>(kOutputReportSize - 1),       //   Report Count (11)
    0x09, 0x02,                                                   //   Usage (0x02)
    0x91, 0x02,                                                   //   Output (Data,Var,Abs)
    0x85, kDeviceInfoReportId,                                    //   Report ID (3)
    0x95, static_cast<std::uint8_t>(kDeviceInfoReportSize - 1),   //   Report Count (31)
    0x09, 0x03,                                                   //   Usage (0x03)
    0xB1, 0x02,                                                   //   Feature (Data,Var,Abs)
    0x85, kCalibrationReportId,                                   //   Report ID (4)
    0x95, static_cast<std::uint8_t>(kCalibrationReportSize - 1),  //   Report Count (23)
    0x09, 0x04,                                                   //   Usage (0x04)
    0xB1, 0x02,                                                   //   Feature (Data,Var,Abs)
    0xC0,                                                         // End Collection
};
}  // namespace

std::span<const std::uint8_t> hid_report_descriptor() {
  return kDescriptor;
}

}  // namespace tsmh::master_devices::protocol
