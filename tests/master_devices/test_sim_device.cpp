#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <thread>

#include "driver_rules.hpp"
#include "master_devices/clock.hpp"
#include "master_devices/sim_device.hpp"

namespace tsmh::master_devices {
namespace {

using namespace std::chrono_literals;

SimSettings simulated(Scenario scenario = PalpateScenario{}) {
  SimSettings s;
  s.simulated_time = true;
  s.scenario = std::move(scenario);
  return s;
}

TEST(SimDevice, SimulatedTimeIsDeterministic) {
  SimDevice a(simulated());
  SimDevice b(simulated());
  a.open();
  b.open();
  a.set_enabled(true);
  b.set_enabled(true);
  for (std::int64_t k = 0; k < 5000; ++k) {
    const std::int64_t t = 7'000'000'000 + k * 1'000'000;  // any start time
    const DeviceReading ra = a.read(t);
    const DeviceReading rb = b.read(t);
    ASSERT_EQ(ra.q, rb.q);
    ASSERT_EQ(ra.qd, rb.qd);
    ASSERT_EQ(ra.t_ns, t);
    const JointArray tau{-0.5 * ra.q[0], -0.5 * ra.q[1]};
    a.write_torque(tau);
    b.write_torque(tau);
  }
  EXPECT_NEAR(a.scenario_time_s(), 4.999, 1e-9);
  EXPECT_TRUE(a.simulated_time());
}

// The master's joints carry the names the rest of the project gives them.
TEST(SimDevice, NamesItsJointsJoint1AndJoint2) {
  SimDevice dev(simulated());
  ASSERT_EQ(dev.spec().dof, 2u);
  EXPECT_EQ(dev.spec().joint_names[0], "joint1");
  EXPECT_EQ(dev.spec().joint_names[1], "joint2");
}

TEST(SimDevice, ReadAdvancesTheWorldToNowLikeTheBareModel) {
  SimDevice dev(simulated());
  dev.open();
  SimulatedOperator op(PalpateScenario{}, 2);
  dev.read(0);
  // Irregular steps in simulated time end up in the same place.
  std::int64_t t = 0;
  for (int k = 0; k < 400; ++k) {
    t += (k % 3 + 1) * 1'000'000;
    dev.read(t);
  }
  for (std::int64_t k = 0; k < t / 1'000'000; ++k)
    op.step(0.001, JointArray{});
  const DeviceReading r = dev.read(t);
  EXPECT_NEAR(r.q[0], op.q()[0], 1e-6);
  EXPECT_NEAR(r.q[1], op.q()[1], 1e-6);
  EXPECT_TRUE(r.buttons.dead_man);
}

TEST(SimDevice, PalpatePressesReachTheScriptedDepthsWithoutFeedback) {
  SimDevice dev(simulated());
  dev.open();
  const PalpateScenario p;
  double soft_max = 0;
  double hard_max = 0;
  const double soft_end = palpate_press(p, p.soft_presses - 1).end_s;
  for (std::int64_t k = 0; k < 20000; ++k) {
    const DeviceReading r = dev.read(k * 1'000'000);
    const double t = k * 1e-3;
    (t < soft_end ? soft_max : hard_max) = std::max(t < soft_end ? soft_max : hard_max, r.q[0]);
  }
  EXPECT_NEAR(soft_max, p.soft_depth_rad, 0.01);
  EXPECT_NEAR(hard_max, p.hard_depth_rad, 0.01);
}

TEST(SimDevice, DisabledOrFaultedRendersNothing) {
  SimDevice dev(simulated());
  dev.open();
  dev.write_torque(JointArray{0.2, 0.2});
  DeviceReading r = dev.read(0);
  r = dev.read(1'000'000);
  EXPECT_EQ(r.tau_commanded[0], 0.0);
  EXPECT_FALSE(r.enabled);
  dev.set_enabled(true);
  dev.write_torque(JointArray{5.0, -0.1});
  r = dev.read(2'000'000);
  EXPECT_EQ(r.tau_commanded[0], 0.3) << "clamped to the peak torque";
  EXPECT_EQ(r.tau_commanded[1], -0.1);
  dev.raise_fault(FaultCode::kHostRequested);
  r = dev.read(3'000'000);
  EXPECT_EQ(r.status, DeviceStatus::kFault);
  EXPECT_EQ(r.tau_commanded[0], 0.0);
  EXPECT_FALSE(dev.last_error().empty());
  EXPECT_TRUE(dev.clear_fault());
  r = dev.read(4'000'000);
  EXPECT_EQ(r.status, DeviceStatus::kOk);
  EXPECT_FALSE(r.enabled);
}

TEST(SimDevice, RealTimeModeStreamsAndZeroesStaleCommands) {
  // The sim's thread runs in real time (streaming is under test), so this
  // waits for its readings; how old the commands are is simulated time.
  const auto clock = std::make_shared<ManualClock>();
  SimSettings s;
  s.command_timeout_ms = 5;
  s.stale_timeout_ms = 2000;  // not what this test is about
  SimDevice dev(s, clock);
  dev.open();
  dev.set_enabled(true);
  // A reading integrated wholly after now (the one in progress may have
  // fetched the previous command).
  const auto reading_after_now = [&] {
    const std::uint64_t seen = dev.read(clock->now_ns()).sequence;
    DeviceReading r = dev.read(clock->now_ns());
    for (int i = 0; i < 2000 && r.sequence < seen + 2; ++i) {
      std::this_thread::sleep_for(1ms);  // the sim's real-time thread integrates meanwhile
      r = dev.read(clock->now_ns());
    }
    return r;
  };
  dev.write_torque(JointArray{0.1, 0.0});
  DeviceReading r = reading_after_now();
  EXPECT_EQ(r.status, DeviceStatus::kOk);
  EXPECT_EQ(r.t_ns, clock->now_ns()) << "stamped with the device's clock";
  EXPECT_EQ(r.tau_commanded[0], 0.1);
  clock->advance(5'000'000);  // no more commands
  r = reading_after_now();
  EXPECT_EQ(r.tau_commanded[0], 0.1) << "a command exactly 5 ms old still renders";
  clock->advance(1'000'000);
  r = reading_after_now();
  EXPECT_EQ(r.status, DeviceStatus::kOk);
  EXPECT_EQ(r.tau_commanded[0], 0.0) << "6 ms old: past command_timeout_ms";
  dev.close();
  EXPECT_EQ(dev.read(clock->now_ns()).status, DeviceStatus::kClosed);
}

TEST(SimDevice, SettingsErrorsNameTheField) {
  auto error_of = [](const std::string& yaml) {
    try {
      config::FieldReader r(YAML::Load(yaml), "server.yaml", "device.settings");
      parse_sim_settings(r);
      r.reject_unknown();
    } catch (const config::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(error_of("time: warp\n")
                .find("server.yaml: device.settings.time: must be 'real' or 'simulated'"),
            std::string::npos);
  EXPECT_NE(error_of("rate_hz: 0\n").find("device.settings.rate_hz: must be > 0"),
            std::string::npos);
  EXPECT_NE(error_of("hand: {stiffness_nm_per_rad: -1}\n")
                .find("device.settings.hand.stiffness_nm_per_rad"),
            std::string::npos);
  EXPECT_NE(error_of("peak_torque_nm: [1, 2, 3]\n")
                .find("peak_torque_nm: must be a number or a list of 2"),
            std::string::npos);
  EXPECT_NE(error_of("rate: 5\n").find("device.settings.rate: unknown key"), std::string::npos);
  EXPECT_EQ(error_of("time: simulated\nscenario: sine\nsine: {frequency_hz: 1}\ndead_man: false\n"),
            "(no error)");
}

TEST(SimDevice, KeepsTheSharedFaultRules) {
  SimDevice dev(simulated());
  dev.open();
  std::int64_t t = 0;
  dev.read(t);
  testing::expect_shared_fault_rules(
      {dev, [&] { return t; }, [&] { return dev.read(t).tau_commanded[0]; },
       [&] { t += 1'000'000; }},
      0.1);
}

}  // namespace
}  // namespace tsmh::master_devices
