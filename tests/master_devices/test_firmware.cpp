// The device side: the emulated console firmware and its mechanism.

#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "master_devices/firmware.hpp"

namespace tsmh::master_devices {
namespace {

using protocol::kOutputReportSize;

constexpr std::int64_t kMs = 1'000'000;

std::vector<std::uint8_t> output(std::uint16_t seq, bool enable, std::int16_t ma0, std::int16_t ma1,
                                 bool clear_fault = false) {
  protocol::OutputReport r;
  r.sequence = seq;
  r.enable = enable;
  r.clear_fault = clear_fault;
  r.current_ma = {ma0, ma1};
  std::vector<std::uint8_t> b(kOutputReportSize);
  EXPECT_TRUE(protocol::encode(r, b).ok());
  return b;
}

protocol::InputReport input(Firmware& fw) {
  std::array<std::uint8_t, protocol::kMaxReportSize> buf{};
  const std::size_t n = fw.make_input_report(buf);
  const auto d = protocol::decode_input(std::span<const std::uint8_t>(buf.data(), n));
  EXPECT_TRUE(d.ok()) << protocol::describe(d.error);
  return d.value;
}

TEST(Firmware, AppliesCommandedCurrentWhenEnabled) {
  Firmware fw(default_console_firmware());
  EXPECT_TRUE(fw.on_output_report(output(1, true, 1000, -500)).code == protocol::ErrorCode::kOk);
  fw.step(kMs);
  EXPECT_DOUBLE_EQ(fw.applied_current_a(0), 1.0);
  EXPECT_DOUBLE_EQ(fw.applied_current_a(1), -0.5);
  const auto in = input(fw);
  EXPECT_TRUE(in.status.torque_enabled);
  EXPECT_EQ(in.last_output_sequence, 1);
  fw.on_output_report(output(2, false, 1000, -500));
  EXPECT_EQ(fw.applied_current_a(0), 0.0);
}

TEST(Firmware, WatchdogZeroesTorqueWhenOutputReportsStop) {
  Firmware fw(default_console_firmware());  // watchdog 50 ms
  fw.on_output_report(output(1, true, 2000, 2000));
  for (int i = 0; i < 50; ++i)
    fw.step(kMs);
  EXPECT_NE(fw.applied_current_a(0), 0.0) << "still within the watchdog time";
  fw.step(2 * kMs);
  EXPECT_TRUE(fw.watchdog_tripped());
  EXPECT_EQ(fw.applied_current_a(0), 0.0);
  EXPECT_EQ(fw.applied_current_a(1), 0.0);
  EXPECT_TRUE(input(fw).status.watchdog_tripped);
  EXPECT_EQ(fw.stats().watchdog_trips, 1u);
  // The next valid report re-arms it.
  fw.on_output_report(output(2, true, 2000, 0));
  fw.step(kMs);
  EXPECT_FALSE(fw.watchdog_tripped());
  EXPECT_DOUBLE_EQ(fw.applied_current_a(0), 2.0);
}

TEST(Firmware, MalformedOutputReportsAreIgnoredAndDoNotFeedTheWatchdog) {
  Firmware fw(default_console_firmware());
  fw.on_output_report(output(1, true, 1000, 0));
  auto bad = output(2, true, 3000, 0);
  bad[4] ^= 0x01;  // CRC now wrong
  for (int i = 0; i < 60; ++i) {
    fw.step(kMs);
    EXPECT_NE(fw.on_output_report(bad).code, protocol::ErrorCode::kOk);
  }
  EXPECT_TRUE(fw.watchdog_tripped());
  EXPECT_EQ(fw.applied_current_a(0), 0.0);
  EXPECT_EQ(fw.stats().output_rejected, 60u);
  EXPECT_EQ(fw.stats().output_accepted, 1u);
}

TEST(Firmware, ClampsToTheCalibratedCurrentLimit) {
  Firmware fw(default_console_firmware());  // hardware max 4000 mA
  protocol::Calibration cal = fw.calibration();
  cal.current_limit_ma = {1500, 5000};  // joint 1 above the hardware: hardware wins
  std::array<std::uint8_t, protocol::kCalibrationReportSize> b{};
  ASSERT_TRUE(protocol::encode(cal, b).ok());
  ASSERT_EQ(fw.set_feature(b).code, protocol::ErrorCode::kOk);
  fw.on_output_report(output(1, true, 3000, -4500));
  EXPECT_DOUBLE_EQ(fw.applied_current_a(0), 1.5);
  EXPECT_DOUBLE_EQ(fw.applied_current_a(1), -4.0);
  EXPECT_TRUE(input(fw).status.current_limited);
}

TEST(Firmware, EStopAndFaultForceZeroTorque) {
  Firmware fw(default_console_firmware());
  fw.on_output_report(output(1, true, 1000, 1000));
  fw.set_buttons(Buttons{true, true, false});
  fw.step(kMs);
  EXPECT_EQ(fw.applied_current_a(0), 0.0);
  EXPECT_TRUE(input(fw).buttons.e_stop);
  fw.set_buttons(Buttons{});
  fw.on_output_report(output(2, true, 1000, 1000));
  EXPECT_NE(fw.applied_current_a(0), 0.0);

  fw.inject_fault(protocol::FirmwareFault::kOverTemperature);
  EXPECT_EQ(fw.applied_current_a(0), 0.0);
  const auto in = input(fw);
  EXPECT_TRUE(in.status.fault);
  EXPECT_EQ(in.fault, protocol::FirmwareFault::kOverTemperature);
  fw.on_output_report(output(3, true, 1000, 1000));  // enable alone does not clear it
  EXPECT_EQ(fw.applied_current_a(0), 0.0);
  fw.on_output_report(output(4, true, 1000, 1000, true));
  EXPECT_NE(fw.applied_current_a(0), 0.0);
}

TEST(Firmware, FeatureReports) {
  Firmware fw(default_console_firmware());
  std::array<std::uint8_t, protocol::kMaxReportSize> b{};
  const std::size_t n = fw.get_feature(protocol::kDeviceInfoReportId, b);
  ASSERT_EQ(n, protocol::kDeviceInfoReportSize);
  const auto info = protocol::decode_device_info(std::span<const std::uint8_t>(b.data(), n));
  ASSERT_TRUE(info.ok());
  EXPECT_EQ(info.value, default_console_firmware().info);
  EXPECT_EQ(fw.get_feature(0x42, b), 0u) << "unknown feature reports stall";
  // DEVICE_INFO is read-only.
  EXPECT_NE(fw.set_feature(std::span<const std::uint8_t>(b.data(), n)).code,
            protocol::ErrorCode::kOk);
  EXPECT_NE(fw.set_feature({}).code, protocol::ErrorCode::kOk);
}

TEST(Firmware, MechanismMovesWithTorqueAndEncoderFollowsOffsetAndDirection) {
  FirmwareConfig cfg = default_console_firmware();
  cfg.encoder_offset_counts = {1000, -500};
  cfg.mount_direction = {1, -1};
  Firmware fw(cfg);
  const auto at_rest = input(fw);
  EXPECT_EQ(at_rest.counts[0], 1000);
  EXPECT_EQ(at_rest.counts[1], -500);
  // Positive current on joint 0 for 100 ms: the joint turns positive.
  for (int i = 0; i < 100; ++i) {
    fw.on_output_report(output(static_cast<std::uint16_t>(i), true, 1000, 0));
    fw.step(kMs);
  }
  EXPECT_GT(fw.position_rad(0), 0.05);
  const auto moved = input(fw);
  const double cpr = cfg.info.counts_per_rev[0] / (2.0 * 3.141592653589793);
  EXPECT_NEAR(moved.counts[0], 1000 + fw.position_rad(0) * cpr, 1.0);
  fw.set_position(1, 0.5);
  EXPECT_NEAR(input(fw).counts[1], -500 - 0.5 * cpr, 1.0);
}

TEST(Firmware, HardStopsHoldTheMechanism) {
  Firmware fw(default_console_firmware());
  fw.set_external_torque(0, 0.5);
  for (int i = 0; i < 3000; ++i)
    fw.step(kMs);
  // 0.5 N m against a 20 N m/rad stop past 1.2 rad: about 1.225 rad.
  EXPECT_NEAR(fw.position_rad(0), 1.2 + 0.5 / 20.0, 0.01);
}

TEST(Firmware, LinkLossDropsEnableAndCurrent) {
  Firmware fw(default_console_firmware());
  fw.on_output_report(output(1, true, 1000, 1000));
  fw.on_link_lost();
  EXPECT_EQ(fw.applied_current_a(0), 0.0);
  EXPECT_FALSE(fw.torque_enabled());
}

TEST(Firmware, SequenceAndClockAdvance) {
  Firmware fw(default_console_firmware());
  const auto a = input(fw);
  fw.step(3 * kMs);
  const auto b = input(fw);
  EXPECT_EQ(protocol::sequence_delta(a.sequence, b.sequence), 1);
  EXPECT_EQ(b.device_time_us - a.device_time_us, 3000u);
}

}  // namespace
}  // namespace tsmh::master_devices
