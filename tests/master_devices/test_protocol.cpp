// The console protocol codec: round trips, byte layout, and that every
// malformed report (short, long, wrong ID, garbage, bit flips, out-of-range
// fields, reserved bits) is an error value, never a crash.

#include <gtest/gtest.h>

#include <array>
#include <random>
#include <string>
#include <vector>

#include "master_devices/protocol.hpp"

namespace tsmh::master_devices::protocol {
namespace {

using Bytes = std::vector<std::uint8_t>;

std::mt19937_64& rng() {
  static std::mt19937_64 r(0x5eed);
  return r;
}
template <class T>
T uniform(T lo, T hi) {
  return std::uniform_int_distribution<T>(lo, hi)(rng());
}
bool coin() {
  return uniform<int>(0, 1) == 1;
}

InputReport random_input() {
  InputReport r;
  r.sequence = uniform<std::uint16_t>(0, 0xFFFF);
  r.device_time_us = uniform<std::uint32_t>(0, 0xFFFFFFFFu);
  for (auto& c : r.counts)
    c = uniform<std::int32_t>(kCountsMin, kCountsMax);
  r.buttons = Buttons{coin(), coin(), coin()};
  r.status = StatusFlags{coin(), coin(), coin(), coin()};
  r.fault = r.status.fault ? static_cast<FirmwareFault>(uniform<int>(1, kFirmwareFaultMax))
                           : FirmwareFault::kNone;
  r.last_output_sequence = uniform<std::uint16_t>(0, 0xFFFF);
  return r;
}

OutputReport random_output() {
  OutputReport r;
  r.sequence = uniform<std::uint16_t>(0, 0xFFFF);
  r.enable = coin();
  r.clear_fault = coin();
  for (auto& c : r.current_ma)
    c = static_cast<std::int16_t>(uniform<int>(-kMaxCurrentMa, kMaxCurrentMa));
  return r;
}

DeviceInfo random_info() {
  DeviceInfo r;
  r.firmware_version = uniform<std::uint16_t>(0, 0xFFFF);
  r.serial_number = uniform<std::uint32_t>(0, 0xFFFFFFFFu);
  r.dof = static_cast<std::uint8_t>(uniform<int>(1, kJoints));
  r.nominal_rate_hz = uniform<std::uint16_t>(1, 0xFFFF);
  for (std::size_t j = 0; j < r.dof; ++j) {
    r.counts_per_rev[j] = uniform<std::uint32_t>(1, 0xFFFFFFFFu);
    r.max_current_ma[j] = static_cast<std::uint16_t>(uniform<int>(0, kMaxCurrentMa));
  }
  r.default_watchdog_ms = uniform<std::uint16_t>(kWatchdogMinMs, kWatchdogMaxMs);
  return r;
}

Calibration random_calibration() {
  Calibration r;
  r.watchdog_ms = uniform<std::uint16_t>(kWatchdogMinMs, kWatchdogMaxMs);
  for (std::size_t j = 0; j < kJoints; ++j) {
    r.zero_offset_counts[j] = uniform<std::int32_t>(kCountsMin, kCountsMax);
    r.current_limit_ma[j] = static_cast<std::uint16_t>(uniform<int>(0, kMaxCurrentMa));
    r.direction[j] = coin() ? 1 : -1;
  }
  return r;
}

template <class Report>
Bytes encoded(const Report& r) {
  std::array<std::uint8_t, kMaxReportSize> buf{};
  const auto n = encode(r, buf);
  EXPECT_TRUE(n.ok()) << describe(n.error);
  return Bytes(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n.value));
}

void reseal(Bytes& b) {
  const std::uint16_t crc = crc16(std::span<const std::uint8_t>(b.data(), b.size() - 2));
  b[b.size() - 2] = static_cast<std::uint8_t>(crc & 0xFF);
  b[b.size() - 1] = static_cast<std::uint8_t>(crc >> 8);
}

// Decodes with every decoder; true if any accepted the bytes.
bool any_decoder_accepts(const Bytes& b) {
  return decode_input(b).ok() || decode_output(b).ok() || decode_device_info(b).ok() ||
         decode_calibration(b).ok();
}

TEST(Crc16, CcittFalseCheckValue) {
  const std::string check = "123456789";
  const Bytes b(check.begin(), check.end());
  EXPECT_EQ(crc16(b), 0x29B1);
}

TEST(Protocol, InputReportRoundTripsForRandomValues) {
  for (int i = 0; i < 20000; ++i) {
    const InputReport r = random_input();
    const Bytes b = encoded(r);
    ASSERT_EQ(b.size(), kInputReportSize);
    const auto d = decode_input(b);
    ASSERT_TRUE(d.ok()) << describe(d.error);
    ASSERT_EQ(d.value, r);
  }
}

TEST(Protocol, OutputReportRoundTripsForRandomValues) {
  for (int i = 0; i < 20000; ++i) {
    const OutputReport r = random_output();
    const Bytes b = encoded(r);
    ASSERT_EQ(b.size(), kOutputReportSize);
    const auto d = decode_output(b);
    ASSERT_TRUE(d.ok()) << describe(d.error);
    ASSERT_EQ(d.value, r);
  }
}

TEST(Protocol, FeatureReportsRoundTripForRandomValues) {
  for (int i = 0; i < 20000; ++i) {
    const DeviceInfo info = random_info();
    const auto di = decode_device_info(encoded(info));
    ASSERT_TRUE(di.ok()) << describe(di.error);
    ASSERT_EQ(di.value, info);
    const Calibration cal = random_calibration();
    const auto dc = decode_calibration(encoded(cal));
    ASSERT_TRUE(dc.ok()) << describe(dc.error);
    ASSERT_EQ(dc.value, cal);
  }
}

TEST(Protocol, InputReportByteLayoutMatchesTheDocument) {
  // The example of docs/hid-protocol.md, byte for byte.
  InputReport r;
  r.sequence = 0x1234;
  r.device_time_us = 0x89ABCDEF;
  r.counts = {1000, -2};
  r.buttons = Buttons{true, false, true};
  r.status = StatusFlags{true, false, false, true};
  r.last_output_sequence = 0x0102;
  const Bytes b = encoded(r);
  const Bytes expected = {0x01, 0x01, 0x34, 0x12, 0xEF, 0xCD, 0xAB, 0x89, 0xE8, 0x03, 0x00, 0x00,
                          0xFE, 0xFF, 0xFF, 0xFF, 0x05, 0x09, 0x02, 0x01, 0x00, 0x00, 0xD3, 0x45};
  EXPECT_EQ(b, expected);
}

TEST(Protocol, OutputReportByteLayoutMatchesTheDocument) {
  OutputReport r;
  r.sequence = 7;
  r.enable = true;
  r.current_ma = {1500, -250};
  const Bytes b = encoded(r);
  const Bytes expected = {0x02, 0x01, 0x07, 0x00, 0xDC, 0x05, 0x06, 0xFF, 0x00, 0x00, 0x72, 0x77};
  EXPECT_EQ(b, expected);
}

TEST(Protocol, EveryWrongLengthIsAnErrorForEveryReport) {
  const std::vector<Bytes> valid = {encoded(random_input()), encoded(random_output()),
                                    encoded(random_info()), encoded(random_calibration())};
  for (const Bytes& b : valid) {
    for (std::size_t n = 0; n <= kMaxReportSize + 8; ++n) {
      if (n == b.size()) continue;
      Bytes cut(n, 0);
      std::copy_n(b.begin(), std::min(n, b.size()), cut.begin());
      EXPECT_FALSE(any_decoder_accepts(cut)) << "length " << n << " of report " << int(b[0]);
    }
  }
  EXPECT_EQ(decode_input(Bytes{}).error.code, ErrorCode::kWrongLength);
  EXPECT_EQ(decode_input(Bytes(kInputReportSize - 1, 0x01)).error.code, ErrorCode::kWrongLength);
}

TEST(Protocol, WrongReportIdIsAnErrorEvenWithAValidCrc) {
  Bytes b = encoded(random_input());
  for (int id = 0; id < 256; ++id) {
    if (id == kInputReportId) continue;
    b[0] = static_cast<std::uint8_t>(id);
    reseal(b);
    const auto d = decode_input(b);
    ASSERT_FALSE(d.ok());
    EXPECT_EQ(d.error.code, ErrorCode::kWrongReportId);
  }
}

TEST(Protocol, EverySingleBitFlipIsDetected) {
  const std::vector<Bytes> valid = {encoded(random_input()), encoded(random_output()),
                                    encoded(random_info()), encoded(random_calibration())};
  for (const Bytes& good : valid) {
    for (std::size_t byte = 0; byte < good.size(); ++byte) {
      for (int bit = 0; bit < 8; ++bit) {
        Bytes b = good;
        b[byte] ^= static_cast<std::uint8_t>(1u << bit);
        EXPECT_FALSE(any_decoder_accepts(b)) << "byte " << byte << " bit " << bit;
      }
    }
  }
}

TEST(Protocol, RandomGarbageIsNeverAccepted) {
  int accepted = 0;
  for (int i = 0; i < 200000; ++i) {
    Bytes b(uniform<std::size_t>(0, 40));
    for (auto& x : b)
      x = uniform<std::uint8_t>(0, 255);
    // Half of them get a plausible report ID to get past the first check.
    if (!b.empty() && coin()) b[0] = static_cast<std::uint8_t>(uniform<int>(1, 4));
    if (any_decoder_accepts(b)) ++accepted;
  }
  EXPECT_EQ(accepted, 0);
}

TEST(Protocol, OutOfRangeCountsAreErrorsNamingTheField) {
  Bytes b = encoded(InputReport{});
  // counts[1] = kCountsMax + 1, little-endian at offset 12.
  const std::uint32_t v = static_cast<std::uint32_t>(kCountsMax) + 1;
  for (int i = 0; i < 4; ++i)
    b[12 + i] = static_cast<std::uint8_t>(v >> (8 * i));
  reseal(b);
  const auto d = decode_input(b);
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.error.code, ErrorCode::kOutOfRange);
  EXPECT_STREQ(d.error.field, "counts[1]");
  EXPECT_NE(describe(d.error).find("counts[1]"), std::string::npos);
  EXPECT_NE(describe(d.error).find("8388608"), std::string::npos);
}

TEST(Protocol, ValidCrcButInvalidFieldsAreErrors) {
  struct Case {
    const char* what;
    std::size_t offset;
    std::uint8_t value;
  };
  const Case input_cases[] = {{"version", 1, 2},     {"buttons", 16, 0x08},
                              {"status", 17, 0x10},  {"fault without flag", 20, 1},
                              {"fault code", 20, 9}, {"reserved", 21, 1}};
  for (const Case& c : input_cases) {
    Bytes b = encoded(InputReport{});
    b[c.offset] = c.value;
    reseal(b);
    EXPECT_FALSE(decode_input(b).ok()) << c.what;
  }
  Bytes out = encoded(OutputReport{});
  out[1] = 0x04;  // undefined flag
  reseal(out);
  EXPECT_EQ(decode_output(out).error.code, ErrorCode::kReservedNotZero);
  out = encoded(OutputReport{});
  out[4] = 0x11;  // current_ma[0] = 10001
  out[5] = 0x27;
  reseal(out);
  EXPECT_EQ(decode_output(out).error.code, ErrorCode::kOutOfRange);

  Calibration cal = random_calibration();
  Bytes cb = encoded(cal);
  cb[16] = 0;  // direction 0
  reseal(cb);
  EXPECT_STREQ(decode_calibration(cb).error.field, "direction[0]");
  DeviceInfo info = random_info();
  Bytes ib = encoded(info);
  ib[8] = 3;  // dof 3
  reseal(ib);
  EXPECT_STREQ(decode_device_info(ib).error.field, "dof");
}

// Every reserved field of every report, and the version byte of the reports
// that carry one, is refused with the report, the field and the value.
TEST(Protocol, ReservedFieldsAndVersionAreRefusedNamingReportFieldAndValue) {
  struct Case {
    Bytes bytes;
    std::size_t offset;
    std::uint8_t value;
    Error (*decode)(const Bytes&);
    ErrorCode code;
    const char* report;
    const char* field;
    std::int64_t reported;
  };
  const auto in = [](const Bytes& b) { return decode_input(b).error; };
  const auto out = [](const Bytes& b) { return decode_output(b).error; };
  const auto info = [](const Bytes& b) { return decode_device_info(b).error; };
  const auto cal = [](const Bytes& b) { return decode_calibration(b).error; };
  const Bytes input = encoded(InputReport{}), output = encoded(OutputReport{});
  const Bytes device = encoded(random_info()), calibration = encoded(random_calibration());
  const Case cases[] = {
      {input, 1, 2, in, ErrorCode::kUnsupportedVersion, "input", "version", 2},
      {input, 21, 5, in, ErrorCode::kReservedNotZero, "input", "reserved", 5},
      {output, 9, 1, out, ErrorCode::kReservedNotZero, "output", "reserved", 256},
      {device, 1, 3, info, ErrorCode::kUnsupportedVersion, "device info", "version", 3},
      {device, 9, 7, info, ErrorCode::kReservedNotZero, "device info", "reserved", 7},
      {device, 29, 1, info, ErrorCode::kReservedNotZero, "device info", "reserved", 1 << 24},
      {calibration, 1, 4, cal, ErrorCode::kReservedNotZero, "calibration", "reserved", 4},
      {calibration, 19, 2, cal, ErrorCode::kReservedNotZero, "calibration", "reserved", 512},
  };
  for (const Case& c : cases) {
    Bytes b = c.bytes;
    b[c.offset] = c.value;
    reseal(b);
    const Error e = c.decode(b);
    EXPECT_EQ(e.code, c.code) << c.report << " byte " << c.offset;
    EXPECT_STREQ(e.report, c.report) << c.report << " byte " << c.offset;
    EXPECT_STREQ(e.field, c.field) << c.report << " byte " << c.offset;
    EXPECT_EQ(e.value, c.reported) << c.report << " byte " << c.offset;
  }
}

TEST(Protocol, EncodersRejectValuesTheDecoderWouldReject) {
  std::array<std::uint8_t, kMaxReportSize> buf{};
  InputReport in;
  in.counts[0] = kCountsMin - 1;
  EXPECT_EQ(encode(in, buf).error.code, ErrorCode::kOutOfRange);
  in = InputReport{};
  in.status.fault = true;  // fault flag without a fault code
  EXPECT_FALSE(encode(in, buf).ok());
  OutputReport out;
  out.current_ma[1] = -kMaxCurrentMa - 1;
  EXPECT_STREQ(encode(out, buf).error.field, "current_ma[1]");
  Calibration cal;  // watchdog 0, direction 0
  EXPECT_FALSE(encode(cal, buf).ok());
  std::array<std::uint8_t, 4> tiny{};
  EXPECT_EQ(encode(InputReport{}, tiny).error.code, ErrorCode::kBufferTooSmall);
}

TEST(Protocol, SequenceDeltaWraps) {
  EXPECT_EQ(sequence_delta(0xFFFF, 0x0000), 1);
  EXPECT_EQ(sequence_delta(10, 13), 3);
}

// A minimal HID short-item parser: enough to check the descriptor declares
// exactly our four reports with the sizes the codec uses.
TEST(Protocol, HidReportDescriptorDeclaresTheCodecsReports) {
  const auto d = hid_report_descriptor();
  std::uint8_t report_id = 0;
  std::uint32_t report_size = 0;
  std::uint32_t report_count = 0;
  std::uint32_t usage_page = 0;
  int depth = 0;
  struct Main {
    std::uint8_t kind;  // 0x80 input, 0x90 output, 0xB0 feature
    std::uint8_t id;
    std::uint32_t bytes;
  };
  std::vector<Main> mains;
  for (std::size_t i = 0; i < d.size();) {
    const std::uint8_t prefix = d[i];
    const std::size_t size = (prefix & 0x3) == 3 ? 4 : (prefix & 0x3);
    ASSERT_LE(i + 1 + size, d.size());
    std::uint32_t data = 0;
    for (std::size_t k = 0; k < size; ++k)
      data |= std::uint32_t{d[i + 1 + k]} << (8 * k);
    switch (prefix & 0xFC) {
      case 0x04:
        usage_page = data;
        break;
      case 0x84:
        report_id = static_cast<std::uint8_t>(data);
        break;
      case 0x74:
        report_size = data;
        break;
      case 0x94:
        report_count = data;
        break;
      case 0xA0:
        ++depth;
        break;
      case 0xC0:
        --depth;
        break;
      case 0x80:
      case 0x90:
      case 0xB0:
        mains.push_back(
            {static_cast<std::uint8_t>(prefix & 0xFC), report_id, report_size * report_count / 8});
        break;
      default:
        break;
    }
    i += 1 + size;
  }
  EXPECT_EQ(usage_page, 0xFF00u);
  EXPECT_EQ(depth, 0);
  ASSERT_EQ(mains.size(), 4u);
  // Report sizes in the descriptor exclude the report-ID byte.
  EXPECT_EQ(mains[0].kind, 0x80);
  EXPECT_EQ(mains[0].id, kInputReportId);
  EXPECT_EQ(mains[0].bytes + 1, kInputReportSize);
  EXPECT_EQ(mains[1].kind, 0x90);
  EXPECT_EQ(mains[1].id, kOutputReportId);
  EXPECT_EQ(mains[1].bytes + 1, kOutputReportSize);
  EXPECT_EQ(mains[2].kind, 0xB0);
  EXPECT_EQ(mains[2].id, kDeviceInfoReportId);
  EXPECT_EQ(mains[2].bytes + 1, kDeviceInfoReportSize);
  EXPECT_EQ(mains[3].kind, 0xB0);
  EXPECT_EQ(mains[3].id, kCalibrationReportId);
  EXPECT_EQ(mains[3].bytes + 1, kCalibrationReportSize);
}

}  // namespace
}  // namespace tsmh::master_devices::protocol
