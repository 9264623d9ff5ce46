// The loop's issue-21 stages in simulated time: the oscillation detector
// fades an oscillating rendered torque and says so in HAPTIC_STATUS; the
// passivity controller, when enabled, keeps the observed energy from going
// negative and reports its state.
#include <gtest/gtest.h>

#include <cmath>

#include "fakes.hpp"
#include "haptics/haptic_loop.hpp"

namespace tsmh::haptics {
namespace {

using testing::FakeDevice;
using testing::FakeLink;
constexpr std::int64_t kMs = 1'000'000;
constexpr double kPi = 3.14159265358979323846;

LoopConfig config(bool passivity) {
  LoopConfig c;
  c.joints = 2;
  c.source = FeedbackSource::kNaive;  // tau_in = R (T1 - T3): the test sets it directly
  for (int j = 0; j < 2; ++j) {
    c.force[j] = {2.0, -1.0, 0.0};  // sign -1: renders +2 x the slave torque
    c.position[j] = {};
    c.limits[j] = {0.8, 100.0};
  }
  c.passivity.enabled = passivity;
  return c;
}

struct Rig {
  explicit Rig(bool passivity = false)
      : loop(config(passivity), device, link, testing::paper_estimators()) {}
  FakeDevice device;
  FakeLink link;
  HapticLoop loop;
  std::int64_t now = 1'000 * kMs;
  double x = 0.0;
  /// One tick; the slave reports tau_in = 0.01 (t1 - 20) N m.
  void tick(double t1, double x_out = 0.0) {
    x += 1e-4;
    link.push(now, x, t1, 20.0, x_out);
    loop.tick(now);
    now += kMs;
  }
};

TEST(HapticLoopDelay, OscillatingTorqueIsFadedAndFlagged) {
  Rig rig;
  // 1 s steady at 0.2 N m rendered (no trip), then a 4 Hz ring of +-0.1 N m.
  for (int i = 0; i < 1000; ++i)
    rig.tick(30.0);
  ASSERT_EQ(rig.loop.state(), LoopState::kEnabled);
  EXPECT_NEAR(rig.device.torque[0], 0.2, 1e-6);
  EXPECT_FALSE(rig.loop.oscillation().tripped());
  int tripped_at = -1;
  for (int i = 0; i < 2000; ++i) {
    rig.tick(30.0 + 5.0 * std::sin(2 * kPi * 4.0 * i * 1e-3));
    if (tripped_at < 0 && rig.loop.oscillation().tripped()) tripped_at = i;
  }
  ASSERT_GE(tripped_at, 0) << "a sustained ring inside the torque limit is caught";
  EXPECT_LT(tripped_at, 1000);
  EXPECT_EQ(rig.device.torque[0], 0.0) << "force faded out";
  EXPECT_EQ(rig.loop.counters().oscillation_trips, 1U);
  const auto& st = rig.link.statuses.back();
  EXPECT_TRUE(st.flags & status_flags::kOscillation);
  EXPECT_EQ(st.oscillation_trips, 1);
  EXPECT_GT(st.oscillation_rms[0], 0.0);
  // The ring stops: after the hold the force comes back.
  for (int i = 0; i < 3000; ++i)
    rig.tick(30.0);
  EXPECT_FALSE(rig.loop.oscillation().tripped());
  EXPECT_NEAR(rig.device.torque[0], 0.2, 1e-6);
  EXPECT_FALSE(rig.link.statuses.back().flags & status_flags::kOscillation);
}

TEST(HapticLoopDelay, DeadManReleaseUnderLoadIsNotAnOscillation) {
  Rig rig;
  for (int cycle = 0; cycle < 5; ++cycle) {
    for (int i = 0; i < 500; ++i)
      rig.tick(36.0);  // 0.32 N m rendered
    rig.device.reading_.buttons.dead_man = false;
    for (int i = 0; i < 100; ++i)
      rig.tick(36.0);
    rig.device.reading_.buttons.dead_man = true;
  }
  EXPECT_EQ(rig.loop.counters().oscillation_trips, 0U);
}

/// The master moves at 1 rad/s while the slave reports a torque pushing the
/// same way and does not move: the channel hands the operator energy that
/// never came in at the slave (what a delay does on hard tissue).
void drive_active(Rig& rig) {
  for (int i = 0; i < 2000; ++i) {
    rig.device.reading_.q[0] = 1e-3 * i;
    rig.tick(30.0);
  }
}

TEST(HapticLoopDelay, PassivityOffObservesOnly) {
  Rig rig(false);
  drive_active(rig);
  EXPECT_LT(rig.loop.passivity(0).observed_energy(), -0.1);
  EXPECT_NEAR(rig.device.torque[0], 0.2, 1e-6) << "off: the torque is untouched";
  const auto& st = rig.link.statuses.back();
  EXPECT_NEAR(st.passivity_energy[0], rig.loop.passivity(0).observed_energy(), 0.01);
  EXPECT_FALSE(st.flags & status_flags::kPassivityActive);
  EXPECT_EQ(rig.loop.counters().passivity_ticks, 0U);
}

TEST(HapticLoopDelay, PassivityOnKeepsTheObservedEnergyAtZeroAndSaysSo) {
  Rig rig(true);
  double min_energy = 0.0;
  for (int i = 0; i < 2000; ++i) {
    rig.device.reading_.q[0] = 1e-3 * i;
    rig.tick(30.0);
    min_energy = std::min(min_energy, rig.loop.passivity(0).observed_energy());
  }
  // Safety's rate limit can trail the correction by a tick or two; the
  // energy then is a few microjoules below 0, never more.
  EXPECT_GT(min_energy, -1e-3);
  EXPECT_LT(rig.device.torque[0], 0.2) << "damped";
  EXPECT_GE(rig.device.torque[0], -0.8) << "within the limit";
  EXPECT_GT(rig.loop.passivity(0).dissipated(), 0.0);
  const auto& st = rig.link.statuses.back();
  EXPECT_TRUE(st.flags & status_flags::kPassivityActive);
  EXPECT_GT(st.passivity_dissipated[0], 0.0);
  EXPECT_GT(rig.loop.counters().passivity_ticks, 1000U);
  // Joint 1 does not move: untouched.
  EXPECT_NEAR(rig.device.torque[1], 0.2, 1e-6);
}

}  // namespace
}  // namespace tsmh::haptics
