// Safety filter, state machine and schedule: pure logic in simulated time.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "haptics/force_mapping.hpp"
#include "haptics/position_mapping.hpp"
#include "haptics/safety_filter.hpp"
#include "haptics/safety_state.hpp"
#include "haptics/tick_schedule.hpp"
#include "haptics/timing_histogram.hpp"

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

TEST(ForceMapping, ScaleSignAndContinuousDeadband) {
  const ForceMapping m{2.0, -1.0, 0.01};
  EXPECT_DOUBLE_EQ(m(0.005), 0.0);
  EXPECT_DOUBLE_EQ(m(0.01), 0.0);
  EXPECT_NEAR(m(0.03), 2.0 * 0.02, 1e-15);
  EXPECT_NEAR(m(-0.03), -2.0 * 0.02, 1e-15);
  EXPECT_TRUE(std::isnan(m(std::nan(""))));  // left for the safety filter to catch
}

TEST(ForceMapping, RendersTheReactionThatPushesTheHandOutOfTheTissue) {
  // Joints turning the same way: the tool presses in + (positive distal
  // torque), so the hand, which moved the master in +, is pushed back in -.
  EXPECT_LT((ForceMapping{1.0, 1.0, 0.0})(0.2), 0.0);
  EXPECT_GT((ForceMapping{1.0, 1.0, 0.0})(-0.2), 0.0);
  // Opposite conventions: the master moved in - to press in +; pushed back in +.
  EXPECT_GT((ForceMapping{1.0, -1.0, 0.0})(0.2), 0.0);
}

TEST(PositionMapping, ClutchFreezesThenContinuesWithoutJump) {
  PositionMapping p({.scale = 0.5, .sign = 1.0});
  EXPECT_DOUBLE_EQ(p.update(0.2, false), 0.1);
  EXPECT_DOUBLE_EQ(p.update(0.4, true), 0.1);  // clutched: frozen
  EXPECT_DOUBLE_EQ(p.update(1.0, true), 0.1);
  EXPECT_DOUBLE_EQ(p.update(1.0, false), 0.1);  // released: no jump
  EXPECT_DOUBLE_EQ(p.update(1.2, false), 0.2);  // then follows with the new offset
  EXPECT_DOUBLE_EQ(p.update(std::nan(""), false), 0.2);
}

TEST(PositionMapping, ClampsToSlaveWorkspace) {
  PositionMapping p({.scale = 1.0, .sign = -1.0, .min_ref = -0.5, .max_ref = 0.5});
  EXPECT_DOUBLE_EQ(p.update(2.0, false), -0.5);
  EXPECT_DOUBLE_EQ(p.update(-0.3, false), 0.3);
}

TEST(SafetyState, Transitions) {
  SafetyStateMachine m;
  SafetyInputs in{.dead_man = false, .device_ok = true};
  EXPECT_EQ(m.update(in), LoopState::kDisabled);
  in.dead_man = true;
  EXPECT_EQ(m.update(in), LoopState::kEnabled);
  in.dead_man = false;
  EXPECT_EQ(m.update(in), LoopState::kDisabled);
  in.dead_man = true;
  m.update(in);
  in.e_stop = true;
  EXPECT_EQ(m.update(in), LoopState::kFault);
  EXPECT_EQ(m.fault(), FaultReason::kEStop);
  in.e_stop = false;
  EXPECT_EQ(m.update(in), LoopState::kFault) << "latched while the dead-man is still held";
  in.dead_man = false;
  EXPECT_EQ(m.update(in), LoopState::kDisabled);
  in.device_ok = false;
  EXPECT_EQ(m.update(in), LoopState::kFault);
  EXPECT_EQ(m.fault(), FaultReason::kDevice);
  in.device_ok = true;
  in.slave_lost = true;
  EXPECT_EQ(m.update(in), LoopState::kFault);
  EXPECT_EQ(m.fault(), FaultReason::kDevice) << "the first cause is kept";
}

TEST(TickSchedule, AbsoluteDeadlinesReBaseOnOverrun) {
  constexpr std::int64_t P = 1'000'000;
  EXPECT_EQ(next_tick(10 * P, 10 * P + 300'000, P).deadline_ns, 11 * P);
  EXPECT_EQ(next_tick(10 * P, 10 * P + 300'000, P).skipped, 0);
  // Finished 2.5 periods late: deadlines 11 and 12 are skipped, next is 13.
  const auto late = next_tick(10 * P, 12 * P + P / 2, P);
  EXPECT_EQ(late.deadline_ns, 13 * P);
  EXPECT_EQ(late.skipped, 2);
  // ...but the tick at 13 is late against 11, the first deadline not run: a
  // stall is measured at its full length, not as the miss of the re-based one.
  EXPECT_EQ(late.due_ns, 11 * P);
  EXPECT_EQ(next_tick(10 * P, 10 * P + 300'000, P).due_ns, 11 * P);
  // Exactly at the next deadline counts as missed (no zero-length sleep burst).
  EXPECT_EQ(next_tick(10 * P, 11 * P, P).deadline_ns, 12 * P);
}

TEST(TimingHistogram, Percentiles) {
  TimingHistogram h;
  for (int i = 1; i <= 1000; ++i)
    h.record(i * 1000);  // 1..1000 us
  const auto s = h.summary();
  EXPECT_EQ(s.count, 1000u);
  EXPECT_NEAR(s.p50_us, 500, 1.0);
  EXPECT_NEAR(s.p99_us, 990, 1.0);
  EXPECT_NEAR(s.max_us, 1000, 1e-9);
  EXPECT_NEAR(s.mean_us, 500.5, 1e-9);
  h.record(50'000'000);  // beyond the linear range: still the exact max
  EXPECT_NEAR(h.summary().max_us, 50000, 1e-9);
}

}  // namespace
}  // namespace tsmh::haptics
