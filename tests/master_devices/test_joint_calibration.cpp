#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "master_devices/joint_calibration.hpp"

namespace tsmh::master_devices {
namespace {

JointProfile joint(int direction, std::int32_t zero) {
  JointProfile j;
  j.counts_per_rad = 1000.0;
  j.direction = direction;
  j.zero_offset_counts = zero;
  j.torque_constant_nm_per_a = 0.2;
  j.current_limit_continuous_a = 1.0;
  j.current_limit_peak_a = 3.0;
  return j;
}

TEST(JointCalibration, CountsAndRadiansRoundTripWithDirectionAndOffset) {
  for (int dir : {1, -1}) {
    const JointProfile j = joint(dir, 500);
    EXPECT_DOUBLE_EQ(counts_to_rad(j, 500), 0.0);
    EXPECT_DOUBLE_EQ(counts_to_rad(j, 1500), dir * 1.0);
    for (double q : {-0.7, 0.0, 0.123, 1.5}) {
      EXPECT_NEAR(counts_to_rad(j, rad_to_counts(j, q)), q, 0.5 / j.counts_per_rad);
    }
  }
}

TEST(JointCalibration, TorqueAndCurrent) {
  const JointProfile j = joint(-1, 0);
  EXPECT_DOUBLE_EQ(torque_to_current_a(j, 0.2), -1.0);
  EXPECT_DOUBLE_EQ(current_to_torque_nm(j, torque_to_current_a(j, 0.37)), 0.37);
  EXPECT_EQ(to_milliamps(1.2345), 1235);
  EXPECT_EQ(to_milliamps(-50.0), -10000) << "clamped to the protocol's range";
  EXPECT_EQ(to_milliamps(std::numeric_limits<double>::quiet_NaN()), 0);
  EXPECT_EQ(to_milliamps(std::numeric_limits<double>::infinity()), 0);
}

TEST(CurrentLimiter, AllowsShortPeaksButFoldsBackSustainedOnes) {
  CurrentLimiter lim(1.0, 3.0, 1.0);
  EXPECT_DOUBLE_EQ(lim.limit(5.0, 0.001), 3.0) << "never above peak";
  lim.reset();
  // A 50 ms peak is fine.
  for (int i = 0; i < 50; ++i)
    EXPECT_DOUBLE_EQ(lim.limit(3.0, 0.001), 3.0);
  // Held at peak, it must fold back to the continuous limit.
  bool folded = false;
  for (int i = 0; i < 2000; ++i)
    folded = folded || lim.limit(3.0, 0.001) == 1.0;
  EXPECT_TRUE(folded);
  // Over a long run the mean square stays near the continuous limit.
  double sum2 = 0;
  for (int i = 0; i < 20000; ++i) {
    const double a = lim.limit(3.0, 0.001);
    sum2 += a * a;
  }
  EXPECT_LT(sum2 / 20000, 1.0 * 1.2);
  // After cooling down, peaks are available again.
  for (int i = 0; i < 5000; ++i)
    lim.limit(0.0, 0.001);
  EXPECT_DOUBLE_EQ(lim.limit(-3.0, 0.001), -3.0);
  EXPECT_DOUBLE_EQ(lim.limit(std::numeric_limits<double>::quiet_NaN(), 0.001), 0.0);
}

TEST(VelocityEstimator, ConvergesToTheSlopeOfARamp) {
  VelocityEstimator v(100.0);
  double q = 0.0;
  for (int i = 0; i < 200; ++i) {
    q += 0.002;  // 2 rad/s at 1 kHz
    v.update(q, 0.001);
  }
  EXPECT_NEAR(v.value(), 2.0, 1e-6);
  EXPECT_DOUBLE_EQ(v.update(q + 1.0, 0.0), v.value()) << "no time step: unchanged";
  v.reset();
  EXPECT_EQ(v.update(5.0, 0.001), 0.0) << "first sample after reset primes";
}

}  // namespace
}  // namespace tsmh::master_devices
