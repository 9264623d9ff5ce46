// DeviceClock: the device's own sample clock mapped onto the host's, so late
// reports look as old as they are. Synthetic (device time, arrival) pairs:
// exact and independent of scheduling.

#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "master_devices/device_clock.hpp"

namespace tsmh::master_devices {
namespace {

constexpr std::int64_t kMs = 1'000'000;
constexpr std::int64_t kHost0 = 5'000 * kMs;  // arbitrary CLOCK_MONOTONIC origin

TEST(DeviceClock, OnTimeReportsAreDatedAtTheirArrivalMinusTheMinimumDelay) {
  DeviceClock clock;
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::int64_t> jitter(0, 300'000);  // 0..300 us of delivery delay
  // 200 us fixed latency plus jitter; the device counts from 1000 us.
  for (int k = 0; k < 2000; ++k) {
    const std::int64_t taken = kHost0 + k * kMs;
    const std::int64_t arrival = taken + 200'000 + (k == 0 ? 0 : jitter(rng));
    const DeviceClock::Sample s = clock.map(static_cast<std::uint32_t>(1000 + k * 1000), arrival);
    EXPECT_LE(s.t_ns, arrival);
    EXPECT_EQ(s.late_ns, arrival - s.t_ns);
    // Dated within the jitter of when it was taken (+ the minimum latency).
    EXPECT_NEAR(static_cast<double>(s.t_ns - (taken + 200'000)), 0.0, 300'000.0) << k;
    EXPECT_LE(s.late_ns, 300'000 + 10'000) << k;
  }
}

TEST(DeviceClock, AReportReadLateIsAsOldAsTheDeviceSays) {
  DeviceClock clock;
  for (int k = 0; k < 100; ++k)
    clock.map(static_cast<std::uint32_t>(k * 1000), kHost0 + k * kMs + 100'000);
  // Reports 100..104 were queued while the host was starved and all read at once, 6 ms after
  // the last one was taken.
  // The estimate may have risen by the tolerance over the 10.9 ms without
  // reports (5000 ppm: 55 us), no more.
  const std::int64_t burst = kHost0 + 104 * kMs + 6 * kMs;
  for (int k = 100; k < 105; ++k) {
    const DeviceClock::Sample s = clock.map(static_cast<std::uint32_t>(k * 1000), burst);
    EXPECT_NEAR(static_cast<double>(s.t_ns), static_cast<double>(kHost0 + k * kMs + 100'000),
                55'000.0);
    EXPECT_GE(s.late_ns, burst - (kHost0 + k * kMs + 100'000) - 55'000)
        << "report " << k << " must count as late";
  }
  // On time again: not late, and the estimate did not move.
  const DeviceClock::Sample s = clock.map(105'000u, kHost0 + 105 * kMs + 100'000);
  EXPECT_LT(s.late_ns, 50'000);
}

TEST(DeviceClock, FollowsADeviceClockSlowerThanTheHostWithinTheTolerance) {
  // The device clock runs 1000 ppm slow: every host millisecond it counts 999 us.
  DeviceClock clock(2000.0);
  std::int64_t worst = 0;
  for (int k = 0; k < 20'000; ++k) {
    const std::int64_t arrival = kHost0 + k * kMs + 50'000;
    const auto device_us = static_cast<std::uint32_t>(k * 999);
    const DeviceClock::Sample s = clock.map(device_us, arrival);
    if (k > 10) worst = std::max(worst, s.late_ns);
  }
  EXPECT_LT(worst, 10'000) << "a drift within the tolerance never looks late";
}

TEST(DeviceClock, ADeviceClockSlowerThanTheToleranceLooksIncreasinglyLate) {
  // The estimate may rise by only 500 ppm: a 2000 ppm slow clock shows up
  // (it would be a broken device clock, and its velocities would be wrong too).
  DeviceClock clock(500.0);
  DeviceClock::Sample s;
  for (int k = 0; k <= 10'000; ++k)
    s = clock.map(static_cast<std::uint32_t>(k * 998), kHost0 + k * kMs);
  EXPECT_NEAR(static_cast<double>(s.late_ns), 10'000 * (2'000.0 - 500.0), 2'000.0);
}

TEST(DeviceClock, AFasterDeviceClockIsFollowedAtOnce) {
  DeviceClock clock(0.0);  // no allowance upwards at all
  for (int k = 0; k < 5000; ++k) {
    const DeviceClock::Sample s =
        clock.map(static_cast<std::uint32_t>(k * 1001), kHost0 + k * kMs + 20'000);
    ASSERT_EQ(s.late_ns, 0) << k;
  }
}

TEST(DeviceClock, WrapsWithTheDeviceCounter) {
  DeviceClock clock;
  const std::uint32_t start = 0xFFFFFFFFu - 2500u;  // wraps after 2.5 ms
  for (int k = 0; k < 10; ++k) {
    const DeviceClock::Sample s =
        clock.map(start + static_cast<std::uint32_t>(k * 1000), kHost0 + k * kMs);
    EXPECT_FALSE(s.restarted && k > 0) << k;
    EXPECT_EQ(s.t_ns, kHost0 + k * kMs) << k;
  }
}

TEST(DeviceClock, RestartsWhenTheDeviceClockJumps) {
  DeviceClock clock;
  for (int k = 0; k < 10; ++k)
    clock.map(static_cast<std::uint32_t>(50'000'000 + k * 1000), kHost0 + k * kMs);
  // The firmware restarted: its clock is back near zero. Without a restart
  // every report would look 50 s late.
  DeviceClock::Sample s = clock.map(1000u, kHost0 + 10 * kMs);
  EXPECT_TRUE(s.restarted);
  EXPECT_EQ(s.late_ns, 0);
  s = clock.map(2000u, kHost0 + 11 * kMs);
  EXPECT_FALSE(s.restarted);
  EXPECT_EQ(s.late_ns, 0);
  // Forward by far more than the host's elapsed time: also a jump.
  s = clock.map(2000u + 5'000'000u, kHost0 + 12 * kMs);
  EXPECT_TRUE(s.restarted);
  // A long host stall with the device clock going on alongside is no jump.
  s = clock.map(2000u + 5'000'000u + 3'000'000u, kHost0 + 12 * kMs + 3000 * kMs);
  EXPECT_FALSE(s.restarted);
  EXPECT_EQ(s.late_ns, 0);
}

TEST(DeviceClock, ResetForgetsTheOffset) {
  DeviceClock clock;
  clock.map(1000u, kHost0);
  clock.reset();
  EXPECT_FALSE(clock.started());
  const DeviceClock::Sample s = clock.map(1000u, kHost0 + 70 * kMs);
  EXPECT_TRUE(s.restarted);
  EXPECT_EQ(s.t_ns, kHost0 + 70 * kMs);
}

}  // namespace
}  // namespace tsmh::master_devices
