// The skeleton driver of docs/adding-a-driver.md compiles, registers, and
// keeps the Device rules: settings errors name the field, torque zero while
// disabled, clamped, NaN ignored, zero after the command timeout, unplug is
// DISCONNECTED with zero torque and recovers.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <chrono>
#include <thread>

#include "driver_rules.hpp"
#include "skeleton_driver.hpp"

namespace tsmh::master_devices::skeleton {
namespace {

// The driver's I/O thread runs in real time: wait (bounded) for it to act.
template <class Pred>
bool eventually(Pred pred) {
  for (int i = 0; i < 400; ++i) {
    if (pred()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return false;
}

struct Rig {
  std::shared_ptr<VendorLink> link = std::make_shared<VendorLink>();
  std::shared_ptr<ManualClock> clock = std::make_shared<ManualClock>(1'000'000'000);
  DriverRegistry registry;
  std::unique_ptr<Device> device;
  Rig() {
    register_skeleton_driver(registry, link, clock);
    device = registry.create("skeleton", YAML::Load("{dof: 3, peak_torque_nm: 0.1}"),
                             {"server.yaml", "device.settings", {}});
    device->open();
  }
  DeviceReading read() { return device->read(clock->now_ns()); }
  void drive(double tau0) {
    JointArray tau{};
    tau[0] = tau0;
    device->write_torque(tau);
  }
};

TEST(SkeletonDriver, SettingsErrorsNameTheField) {
  DriverRegistry registry;
  register_skeleton_driver(registry, std::make_shared<VendorLink>());
  try {
    registry.create("skeleton", YAML::Load("{dof: 9}"), {"server.yaml", "device.settings", {}});
    FAIL() << "dof 9 accepted";
  } catch (const config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("device.settings.dof"), std::string::npos) << e.what();
  }
  EXPECT_THROW(registry.create("skeleton", YAML::Load("{rate: 5}"), {}), config::ConfigError);
}

TEST(SkeletonDriver, NamesItsJointsAsTheProjectDoes) {
  Rig rig;
  const DeviceSpec& spec = rig.device->spec();
  ASSERT_EQ(spec.dof, 3u);
  EXPECT_EQ(spec.joint_names[0], "joint1");
  EXPECT_EQ(spec.joint_names[1], "joint2");
  EXPECT_EQ(spec.joint_names[2], "joint3");
}

TEST(SkeletonDriver, TorqueFollowsTheRules) {
  Rig rig;
  ASSERT_TRUE(eventually([&] { return rig.read().sequence > 2; }));
  EXPECT_EQ(rig.read().status, DeviceStatus::kOk);
  EXPECT_EQ(rig.read().dof, 3U);

  rig.drive(0.05);  // disabled: nothing reaches the device
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_EQ(rig.link->last_torque[0].load(), 0.0);

  rig.device->set_enabled(true);
  rig.read();
  rig.drive(10.0);  // clamped to the peak
  ASSERT_TRUE(eventually([&] { return rig.link->last_torque[0].load() == 0.1; }));
  rig.drive(std::nan(""));
  ASSERT_TRUE(eventually([&] { return rig.link->last_torque[0].load() == 0.0; }));

  rig.drive(0.05);
  ASSERT_TRUE(eventually([&] { return rig.link->last_torque[0].load() == 0.05; }));
  rig.clock->advance(21'000'000);  // no write_torque() for longer than the command timeout
  EXPECT_TRUE(eventually([&] { return rig.link->last_torque[0].load() == 0.0; }));
}

TEST(SkeletonDriver, UnplugIsDisconnectedWithZeroTorqueAndRecovers) {
  Rig rig;
  rig.device->set_enabled(true);
  ASSERT_TRUE(eventually([&] { return rig.read().status == DeviceStatus::kOk; }));
  rig.link->plugged.store(false);
  ASSERT_TRUE(eventually([&] { return rig.read().status == DeviceStatus::kDisconnected; }));
  rig.drive(0.05);
  const auto r = rig.read();
  EXPECT_FALSE(r.enabled);
  EXPECT_EQ(r.tau_commanded[0], 0.0);
  EXPECT_NE(rig.device->last_error().find("unplugged"), std::string::npos);
  rig.link->plugged.store(true);
  EXPECT_TRUE(eventually([&] { return rig.read().status == DeviceStatus::kOk; }));
  EXPECT_FALSE(rig.read().enabled) << "back disabled after a reconnect";
}

TEST(SkeletonDriver, KeepsTheSharedFaultRules) {
  Rig rig;
  ASSERT_TRUE(eventually([&] { return rig.read().status == DeviceStatus::kOk; }));
  testing::expect_shared_fault_rules(
      {*rig.device, [&] { return rig.clock->now_ns(); },
       [&] { return rig.link->last_torque[0].load(); },
       [] { std::this_thread::sleep_for(std::chrono::milliseconds(1)); }},
      0.05);
}

}  // namespace
}  // namespace tsmh::master_devices::skeleton
