// libFuzzer target: every decoder must return an error or a value for any
// bytes, never crash, read out of bounds or trip UB. Each input is tried
// as is and with a valid CRC appended/patched in, so the fuzzer also reaches
// the field validation behind the checksum.
//   build-fuzz/bin/fuzz_master_devices_decoder -max_total_time=60

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "master_devices/firmware.hpp"
#include "master_devices/protocol.hpp"

namespace p = tsmh::master_devices::protocol;

namespace {
void decode_all(std::span<const std::uint8_t> b) {
  const auto in = p::decode_input(b);
  if (in.ok()) {
    // A decoded report must survive a round trip unchanged.
    std::array<std::uint8_t, p::kMaxReportSize> out{};
    const auto n = p::encode(in.value, out);
    if (!n.ok() || !std::equal(b.begin(), b.end(), out.begin())) __builtin_trap();
  }
  (void)p::decode_output(b);
  (void)p::decode_device_info(b);
  (void)p::decode_calibration(b);
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> raw(data, size);
  decode_all(raw);
  if (size >= 3 && size <= p::kMaxReportSize) {
    std::array<std::uint8_t, p::kMaxReportSize> fixed{};
    std::copy(raw.begin(), raw.end(), fixed.begin());
    const std::uint16_t crc = p::crc16(std::span<const std::uint8_t>(fixed.data(), size - 2));
    fixed[size - 2] = static_cast<std::uint8_t>(crc & 0xFF);
    fixed[size - 1] = static_cast<std::uint8_t>(crc >> 8);
    decode_all(std::span<const std::uint8_t>(fixed.data(), size));
    // The firmware must also shrug off anything as an output or feature report.
    tsmh::master_devices::Firmware fw(tsmh::master_devices::default_console_firmware());
    (void)fw.on_output_report(std::span<const std::uint8_t>(fixed.data(), size));
    (void)fw.set_feature(std::span<const std::uint8_t>(fixed.data(), size));
  }
  return 0;
}
