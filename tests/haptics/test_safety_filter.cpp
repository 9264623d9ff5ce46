// The safety filter: limits, NaN, stale fade and rate limit, whatever the input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "haptics/safety_filter.hpp"

namespace tsmh::haptics {
namespace {

std::array<JointSafetyLimits, kMaxJoints> limits(double max, double rate) {
  std::array<JointSafetyLimits, kMaxJoints> l{};
  l.fill({max, rate});
  return l;
}

TEST(SafetyFilter, NeverExceedsLimitsWhateverTheInput) {
  SafetyFilter f(2, limits(0.5, 50.0), {});
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> wild(-1e6, 1e6);
  std::uniform_int_distribution<int> kind(0, 9);
  const double inf = std::numeric_limits<double>::infinity();
  JointArray prev{};
  for (int i = 0; i < 200000; ++i) {
    JointArray req{};
    for (int j = 0; j < 2; ++j) {
      const int k = kind(rng);
      req[j] = k == 0   ? std::nan("")
               : k == 1 ? inf
               : k == 2 ? -inf
               : k == 3 ? 1e300
                        : wild(rng) * 1e-5;
    }
    const double age = kind(rng) == 0 ? std::nan("") : (i % 5000 < 4000 ? 0.001 : 0.5);
    const auto out = f.apply(req, 1e-3, age, true);
    for (int j = 0; j < 2; ++j) {
      ASSERT_TRUE(std::isfinite(out.torque[j]));
      ASSERT_LE(std::fabs(out.torque[j]), 0.5);
      ASSERT_LE(std::fabs(out.torque[j] - prev[j]), 50.0 * 1e-3 + 1e-12) << i;
    }
    prev = out.torque;
  }
}

TEST(SafetyFilter, DisablingZeroesAtOnce) {
  SafetyFilter f(1, limits(1.0, 10.0), {});
  JointArray req{};
  req[0] = 0.8;
  for (int i = 0; i < 1000; ++i)
    f.apply(req, 1e-3, 0.0, true);
  EXPECT_NEAR(f.last().torque[0], 0.8, 1e-12);
  const auto off = f.apply(req, 1e-3, 0.0, false);
  EXPECT_EQ(off.torque[0], 0.0);
  EXPECT_TRUE(off.flags & safety_flags::kDisabled);
}

TEST(SafetyFilter, StaleSourceFadesToZeroAndRecoversSmoothly) {
  const SafetyTiming timing{0.020, 0.050, 0.200};
  SafetyFilter f(1, limits(1.0, 1000.0), timing);
  JointArray req{};
  req[0] = 0.6;
  double t = 0.0, last_fresh = 0.0;
  for (; t < 1.0; t += 1e-3) {
    f.apply(req, 1e-3, 0.0, true);
    last_fresh = t;
  }
  EXPECT_NEAR(f.last().torque[0], 0.6, 1e-9);
  // Source dies: age grows. Full torque until 20 ms, then a 50 ms fade.
  double zero_at = -1.0;
  for (; t < 1.5; t += 1e-3) {
    const double age = t - last_fresh;
    const auto out = f.apply(req, 1e-3, age, true);
    if (age <= 0.020) {
      EXPECT_NEAR(out.torque[0], 0.6, 1e-9);
    }
    if (out.torque[0] == 0.0 && zero_at < 0) zero_at = age;
  }
  EXPECT_GT(zero_at, 0.020 + 0.045);
  EXPECT_LT(zero_at, 0.020 + 0.055);
  // Fresh again: back to full over 200 ms, monotonically, no step.
  double prev = 0.0;
  for (int i = 0; i < 300; ++i) {
    const auto out = f.apply(req, 1e-3, 0.0, true);
    EXPECT_GE(out.torque[0], prev - 1e-12);
    EXPECT_LE(out.torque[0] - prev, 0.6 * 1e-3 / 0.2 + 1e-12);
    prev = out.torque[0];
  }
  EXPECT_NEAR(prev, 0.6, 1e-9);
}

TEST(SafetyFilter, RateLimitShapesASuddenStep) {
  SafetyFilter f(1, limits(1.0, 20.0), {});
  JointArray req{};
  for (int i = 0; i < 300; ++i)
    f.apply(req, 1e-3, 0.0, true);  // gain up
  req[0] = 1.0;
  int ticks = 0;
  while (f.apply(req, 1e-3, 0.0, true).torque[0] < 1.0 - 1e-12)
    ++ticks;
  EXPECT_NEAR(ticks, 49, 1);  // 1 N m at 20 N m/s = 50 ms
}

TEST(SafetyFilter, RefusesBadLimitsNamingTheField) {
  try {
    SafetyFilter f(2, limits(std::nan(""), 1.0), {});
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joints[0].max_torque_nm"), std::string::npos);
  }
  EXPECT_THROW(SafetyFilter(2, limits(1.0, 0.0), {}), std::invalid_argument);
  EXPECT_THROW(SafetyFilter(0, limits(1.0, 1.0), {}), std::invalid_argument);
}

}  // namespace
}  // namespace tsmh::haptics
