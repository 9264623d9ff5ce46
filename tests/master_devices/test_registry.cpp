#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

#include "config/field_reader.hpp"
#include "master_devices/builtin_drivers.hpp"
#include "master_devices/clock.hpp"
#include "master_devices/registry.hpp"

namespace tsmh::master_devices {
namespace {

DriverRegistry builtin() {
  DriverRegistry r;
  register_builtin_drivers(r);
  return r;
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Registry, HasTheBuiltinDrivers) {
  const DriverRegistry r = builtin();
  for (const char* name : {"hid", "usb", "emulator", "sim", "haply"})
    EXPECT_TRUE(r.has(name)) << name;
  EXPECT_FALSE(r.has("lcm")) << "lcm lives in its own target";
  EXPECT_EQ(r.drivers().size(), 5u);
}

TEST(Registry, RejectsDuplicateAndUnknownDrivers) {
  DriverRegistry r = builtin();
  EXPECT_THROW(
      r.add("sim", "again",
            [](const YAML::Node&, const DriverContext&) { return std::unique_ptr<Device>(); }),
      std::invalid_argument);
  DriverContext ctx;
  ctx.source = "server.yaml";
  const std::string e = error_of([&] { r.create("phantom", YAML::Node(), ctx); });
  EXPECT_NE(e.find("server.yaml: unknown device driver 'phantom' (registered: emulator, haply, "
                   "hid, sim, usb)"),
            std::string::npos)
      << e;
}

TEST(Registry, CreatesADeviceFromAServerConfigNode) {
  const YAML::Node config = YAML::Load(R"(
device:
  driver: sim
  settings:
    time: simulated
    scenario: sine
)");
  DriverContext ctx{"server.yaml", "device", {}};
  auto dev = create_device(builtin(), config["device"], ctx);
  ASSERT_TRUE(dev);
  EXPECT_EQ(dev->spec().driver, "sim");
  EXPECT_TRUE(dev->simulated_time());
  dev->open();
  EXPECT_EQ(dev->read(0).status, DeviceStatus::kOk);

  const YAML::Node bad = YAML::Load("device:\n  driver: sim\n  settings:\n    rate_hz: -5\n");
  const std::string e = error_of([&] { create_device(builtin(), bad["device"], ctx); });
  EXPECT_NE(e.find("server.yaml: device.settings.rate_hz: must be > 0 (line 4)"), std::string::npos)
      << e;
  const YAML::Node typo = YAML::Load("device:\n  drivr: sim\n");
  EXPECT_NE(error_of([&] {
              create_device(builtin(), typo["device"], ctx);
            }).find("device.driver: missing"),
            std::string::npos);
}

TEST(Registry, EmulatorDriverRunsTheConsoleCodeWithASimulatedOperator) {
  const YAML::Node settings = YAML::Load("operator: {scenario: sine}\nstale_timeout_ms: 2000\n");
  auto dev = builtin().create("emulator", settings);
  dev->open();
  // A real sleep: the registry's emulator is paced in real time by its own
  // thread, and that streaming is what this test checks.
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const DeviceReading r = dev->read(realtime::monotonic_now_ns());  // the registry's default clock
  EXPECT_EQ(r.status, DeviceStatus::kOk);
  EXPECT_GT(r.sequence, 100u);
  EXPECT_GT(std::abs(r.q[0]), 0.01) << "the simulated hand moves the emulated handle";
  EXPECT_TRUE(r.buttons.dead_man);
  dev->close();
}

TEST(Registry, DevicesReadTheClockTheRegistryWasGiven) {
  const auto clock = std::make_shared<ManualClock>(5'000'000'000);
  BuiltinDriverOptions options;
  options.clock = clock;
  DriverRegistry registry;
  register_builtin_drivers(registry, options);
  auto dev = registry.create("sim", YAML::Load("stale_timeout_ms: 20\n"));
  dev->open();
  const DeviceReading r = dev->read(clock->now_ns());
  EXPECT_EQ(r.t_ns, 5'000'000'000) << "stamped with the given clock, not CLOCK_MONOTONIC";
  EXPECT_EQ(r.status, DeviceStatus::kOk);
  dev->close();
}

TEST(Registry, ConsoleDriversSelectProfilesByNameOrFile) {
  DriverContext ctx{"server.yaml", "device.settings", {}};
  const DriverRegistry r = builtin();
  EXPECT_NO_THROW(r.create("hid", YAML::Load("profile: tsm-console-2dof\n"), ctx));
  const std::string unknown =
      error_of([&] { r.create("hid", YAML::Load("profile: falcon\n"), ctx); });
  EXPECT_NE(
      unknown.find("device.settings.profile: unknown profile 'falcon' (known: tsm-console-2dof"),
      std::string::npos)
      << unknown;
  // A file relative to the config's directory.
  const auto dir =
      std::filesystem::temp_directory_path() / ("tsmh_registry_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::filesystem::copy_file(
      std::string(TSMH_SOURCE_DIR) + "/master_devices/profiles/tsm-console-2dof.yaml",
      dir / "mine.yaml", std::filesystem::copy_options::overwrite_existing);
  ctx.base_dir = dir;
  auto dev = r.create("emulator", YAML::Load("profile: mine.yaml\n"), ctx);
  EXPECT_EQ(dev->spec().model, "tsm-console-2dof");
  EXPECT_NO_THROW(r.create("usb", YAML::Load("sysfs_fallback: false\nstale_periods: 4\n"), ctx));
  const std::string typo =
      error_of([&] { r.create("hid", YAML::Load("reconect_interval_ms: 5\n"), ctx); });
  EXPECT_NE(typo.find("device.settings.reconect_interval_ms: unknown key"), std::string::npos)
      << typo;
  std::filesystem::remove_all(dir);
}

TEST(Registry, ListsConnectedDevicesFromEveryLister) {
  DriverRegistry r;
  auto make = [](const YAML::Node&, const DriverContext&) { return std::unique_ptr<Device>(); };
  r.add("a", "", make, [] {
    return std::vector<ConnectedDevice>{
        {"a", "/dev/hidraw7", 0x1209, 0x0001, "S1", "console", "tsm-console-2dof"}};
  });
  r.add("broken", "", make,
        []() -> std::vector<ConnectedDevice> { throw std::runtime_error("no usbfs"); });
  r.add("none", "", make);
  const auto found = r.list_connected();
  ASSERT_EQ(found.size(), 1u);
  const std::string text = format_connected(found);
  EXPECT_NE(text.find("a\t/dev/hidraw7\t1209:0001\tprofile=tsm-console-2dof\tserial=S1"),
            std::string::npos)
      << text;
  EXPECT_EQ(format_connected({}), "no known master devices connected\n");
  // The real listers run without hardware and find nothing here.
  EXPECT_NO_THROW(builtin().list_connected());
}

TEST(Udev, RulesFileGrantsUaccessForTheShippedProfileBeforeSeatLate) {
  const std::filesystem::path rules =
      std::string(TSMH_SOURCE_DIR) + "/master_devices/udev/70-tsm-haptics.rules";
  std::ifstream in(rules);
  ASSERT_TRUE(in) << rules;
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  EXPECT_LT(rules.filename().string(), std::string("73-seat-late.rules"));
  const DeviceProfile p = builtin_console_profile();
  char vid[8];
  char pid[8];
  std::snprintf(vid, sizeof vid, "%04x", p.vendor_id);
  std::snprintf(pid, sizeof pid, "%04x", p.product_id);
  int rules_with_ids = 0;
  std::istringstream lines(s);
  for (std::string line; std::getline(lines, line);) {
    if (line.empty() || line[0] == '#') continue;
    EXPECT_NE(line.find("TAG+=\"uaccess\""), std::string::npos) << line;
    if (line.find(std::string("\"") + vid + "\"") != std::string::npos &&
        line.find(std::string("\"") + pid + "\"") != std::string::npos) {
      ++rules_with_ids;
    }
  }
  EXPECT_EQ(rules_with_ids, 2) << "one rule for hidraw, one for the USB device node";
  EXPECT_NE(s.find("SUBSYSTEM==\"hidraw\""), std::string::npos);
  EXPECT_NE(s.find("SUBSYSTEM==\"usb\""), std::string::npos);
}

}  // namespace
}  // namespace tsmh::master_devices
