// PassivityChannel on synthetic port signals: the two-port
// observer's bookkeeping, the controller keeping the observed energy >= 0,
// and the controller changing nothing while the energy is positive.
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <limits>

#include "haptics/passivity.hpp"

namespace tsmh::haptics {
namespace {

constexpr double kDt = 0.001;
constexpr double kPi = 3.14159265358979323846;

TEST(PassivityObserver, AccountsEachPortsInAndOutEnergy) {
  PassivityChannel p;  // controller off: observes only
  // Master moves +0.1 rad in 100 ticks against -0.2 N m: the operator puts
  // 0.02 J in. Then back -0.1 rad with -0.2 N m: 0.02 J out to the operator.
  for (int i = 0; i <= 100; ++i) {
    EXPECT_DOUBLE_EQ(p.control(0.001 * i, -0.2, kDt), -0.2);
    p.commit(-0.2);
  }
  for (int i = 99; i >= 0; --i) {
    p.control(0.001 * i, -0.2, kDt);
    p.commit(-0.2);
  }
  EXPECT_NEAR(p.master_port().in, 0.02, 1e-12);
  EXPECT_NEAR(p.master_port().out, 0.02, 1e-12);
  // Slave port: pushed 0.05 rad into -0.4 N m (0.02 J out to the tissue),
  // then the tissue pushes it back 0.05 rad (0.02 J in).
  for (int i = 0; i <= 50; ++i)
    p.slave_sample(-0.4, 0.001 * i);
  for (int i = 49; i >= 0; --i)
    p.slave_sample(-0.4, 0.001 * i);
  EXPECT_NEAR(p.slave_port().out, 0.02, 1e-12);
  EXPECT_NEAR(p.slave_port().in, 0.02, 1e-12);
  EXPECT_NEAR(p.observed_energy(), 0.0, 1e-12) << "W_M = E_in_S - E_out_M";
  EXPECT_NEAR(slave_side_energy(p.master_port().in, p.slave_port().out), 0.0, 1e-12);
  // Non-finite input is skipped, never poisons the sums.
  p.slave_sample(std::nan(""), 0.1);
  p.commit(std::numeric_limits<double>::infinity());
  EXPECT_TRUE(std::isfinite(p.observed_energy()));
}

/// A delayed position-force loop on synthetic signals: the master follows a
/// sine, the slave follows the master `delay` ticks later into a spring, and
/// the master renders the spring's torque another `delay` ticks later. The
/// delay makes the channel active: it hands the operator energy that never
/// came in at the slave.
struct DelayedSpring {
  int delay;
  double k = 1.5;
  std::deque<double> fwd;
  std::deque<std::pair<double, double>> back;  // (torque, angle) of a slave sample
  double x = 0.0;
  explicit DelayedSpring(int d)
      : delay(d), fwd(static_cast<std::size_t>(d), 0.0), back(static_cast<std::size_t>(d)) {}
  /// One tick: master at q; returns the torque the master receives now and
  /// reports the slave's sample to `p`.
  double step(double q, PassivityChannel& p) {
    fwd.push_back(q);
    x = fwd.front();
    fwd.pop_front();
    const double f = -k * std::max(0.0, x);  // one-sided tissue at 0
    // The slave's sample reaches the master `delay` ticks later; the master
    // side accounts it then (E_in_S as received).
    back.emplace_back(f, x);  // torque and angle of the same instant, as in SLAVE_STATE
    const auto [rendered, angle] = back.front();
    back.pop_front();
    p.slave_sample(rendered, angle);
    return rendered;
  }
};

TEST(PassivityController, KeepsTheObservedEnergyNonNegativeUnderDelay) {
  for (const int delay : {10, 50}) {
    PassivityConfig on;
    on.enabled = true;
    on.max_damping_nms_per_rad = 100.0;  // unbounded for the property
    PassivityChannel off_pc, on_pc(on);
    DelayedSpring off_link(delay), on_link(delay);
    double min_off = 0, min_on = 0;
    for (int i = 0; i < 5000; ++i) {
      const double q = 0.2 * std::sin(2 * kPi * 1.5 * i * kDt);
      // The slave side sees the same motion in both runs (position forward).
      off_pc.commit(off_pc.control(q, off_link.step(q, off_pc), kDt));
      on_pc.commit(on_pc.control(q, on_link.step(q, on_pc), kDt));
      min_off = std::min(min_off, off_pc.observed_energy());
      min_on = std::min(min_on, on_pc.observed_energy());
      ASSERT_GE(on_pc.observed_energy(), -1e-12) << "tick " << i << " delay " << delay;
    }
    EXPECT_LT(min_off, -1e-3) << "without the controller the delayed channel is active";
    EXPECT_GT(on_pc.dissipated(), 0.0);
  }
}

TEST(PassivityController, ChangesNothingWhileTheObservedEnergyIsPositive) {
  PassivityConfig on;
  on.enabled = true;
  PassivityChannel pc(on);
  // The slave port has put 1 J in (the tissue pushed back hard).
  pc.slave_sample(-10.0, 0.0);
  pc.slave_sample(-10.0, -0.1);
  ASSERT_NEAR(pc.observed_energy(), 1.0, 1e-12);
  for (int i = 0; i < 3000; ++i) {
    const double q = 0.1 * std::sin(2 * kPi * 2.0 * i * kDt);
    const double request = -0.25 * std::cos(2 * kPi * 2.0 * i * kDt);  // active
    const double out = pc.control(q, request, kDt);
    ASSERT_EQ(out, request) << "tick " << i;
    EXPECT_FALSE(pc.active());
    pc.commit(out);
  }
  EXPECT_GT(pc.observed_energy(), 0.0);
  EXPECT_EQ(pc.dissipated(), 0.0);
}

TEST(PassivityController, DampingIsBoundedAndOffMeansUnchanged) {
  PassivityConfig on;
  on.enabled = true;
  on.max_damping_nms_per_rad = 0.5;
  PassivityChannel pc(on), off;
  for (int i = 0; i < 1000; ++i) {
    const double q = 0.05 * i * kDt;  // 0.05 rad/s
    const double request = 0.3;       // pushes the way the master moves: active
    const double out = pc.control(q, request, kDt);
    EXPECT_LE(pc.damping(), 0.5 + 1e-12);
    EXPECT_GE(out, request - 0.5 * 0.05 - 1e-12);
    pc.commit(out);
    EXPECT_EQ(off.control(q, request, kDt), request);
    off.commit(request);
  }
  EXPECT_LT(pc.observed_energy(), 0.0) << "bounded: it cannot always catch up, and says so";
  EXPECT_GT(pc.observed_energy(), off.observed_energy());
  EXPECT_THROW(PassivityChannel({.enabled = true, .max_damping_nms_per_rad = 0.0}),
               std::invalid_argument);
}

TEST(PassivityController, ADeficitIsRepaidByABoundedBrakeThatLetsGo) {
  PassivityConfig on;
  on.enabled = true;
  on.max_brake_nm = 0.02;
  PassivityChannel pc(on);
  // Safety's rate limit renders 0.2 N m for a tick where the controller cut
  // it: 0.2 N m along 1 mrad of motion is 2e-4 J the channel did not have.
  pc.control(0.0, 0.2, kDt);
  pc.commit(0.2);
  pc.control(0.001, 0.2, kDt);
  pc.commit(0.2);
  ASSERT_NEAR(pc.observed_energy(), -2e-4, 1e-12);
  // The master keeps moving at 1 rad/s with the same active request: the
  // controller brakes, never harder than max_brake_nm, until repaid.
  int braking_ticks = 0;
  for (int i = 2; i < 100; ++i) {
    const double out = pc.control(0.001 * i, 0.2, kDt);
    ASSERT_GE(out, -0.02 - 1e-12) << "tick " << i;
    if (out < 0.0) ++braking_ticks;
    pc.commit(out);
  }
  EXPECT_EQ(braking_ticks, 10) << "2e-4 J at 0.02 N m x 1 mrad per tick";
  EXPECT_NEAR(pc.observed_energy(), 0.0, 1e-12) << "repaid, then held at 0";
  EXPECT_THROW(PassivityChannel({.enabled = true, .max_brake_nm = -1.0}), std::invalid_argument);
}

TEST(PassivityController, ResetStartsAfresh) {
  PassivityChannel pc;
  pc.slave_sample(-1.0, 0.0);
  pc.slave_sample(-1.0, -0.1);
  pc.control(0.0, 0.0, kDt);
  pc.reset();
  EXPECT_EQ(pc.observed_energy(), 0.0);
  EXPECT_EQ(pc.slave_port().in, 0.0);
  pc.slave_sample(-1.0, 5.0);  // first sample after a reset: no displacement counted
  EXPECT_EQ(pc.slave_port().in + pc.slave_port().out, 0.0);
}

}  // namespace
}  // namespace tsmh::haptics
