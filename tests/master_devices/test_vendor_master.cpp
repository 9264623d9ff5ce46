// The vendor interface of the LCM adapter (vendor_master.hpp): stubs that
// refuse to run without their SDK, the simulated device, and the shipped
// Cartesian profiles of such masters through the mapping layer (buttons by
// name, force limits in the device's units).

#include <gtest/gtest.h>

#include <cmath>

#include "master_devices/axis_mapping.hpp"
#include "master_devices/vendor_master.hpp"

namespace md = tsmh::master_devices;

namespace {

md::MasterProfile shipped(const std::string& name) {
  return md::load_master_profile(std::string(TSMH_SOURCE_DIR) +
                                 "/master_devices/profiles/masters/" + name + ".yaml");
}

}  // namespace

TEST(VendorMaster, StubsRefuseToRunNamingWhatIsMissing) {
  const md::MasterProfile falcon = shipped("novint-falcon");
  const struct {
    const char* name;
    const char* says;
  } cases[] = {{"novint-falcon", "Novint's firmware"},
               {"force-dimension", "DHD/DRD SDK"},
               {"openhaptics", "OpenHaptics HD API"}};
  for (const auto& c : cases) {
    auto device = md::make_vendor_master(c.name, falcon, 1000.0, 0.01);
    try {
      device->open();
      FAIL() << c.name << " opened without its SDK";
    } catch (const md::DeviceError& e) {
      const std::string what = e.what();
      EXPECT_EQ(what.rfind(std::string(c.name) + ": this build cannot drive it: ", 0), 0U) << what;
      EXPECT_NE(what.find(c.says), std::string::npos) << what;
      EXPECT_NE(what.find("Implement tsmh::master_devices::VendorMaster"), std::string::npos);
    }
    md::JointArray x{};
    std::uint32_t buttons = 0;
    EXPECT_FALSE(device->read(x, buttons)) << "a stub never delivers a sample";
  }
  try {
    md::make_vendor_master("phantom", falcon, 1000.0, 0.01);
    FAIL();
  } catch (const tsmh::config::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'phantom' is not a known vendor master (expected one "
                                         "of: simulated, novint-falcon, force-dimension, "
                                         "openhaptics)"),
              std::string::npos)
        << e.what();
  }
}

TEST(VendorMaster, SimulatedHandleMovesAroundTheWorkspaceCentreAndFeelsTheEffort) {
  const md::MasterProfile falcon = shipped("novint-falcon");
  md::SimulatedVendorMaster free(falcon, 1000.0, 0.01), pushed(falcon, 1000.0, 0.01);
  pushed.write([] {
    md::JointArray f{};
    f[2] = 0.05;  // a force along z
    return f;
  }());
  md::JointArray x_free{}, x_pushed{};
  std::uint32_t buttons = 0;
  double largest = 0.0;
  for (int i = 0; i < 3000; ++i) {
    ASSERT_TRUE(free.read(x_free, buttons));
    pushed.read(x_pushed, buttons);
    largest = std::max(largest, std::abs(x_free[0]));
  }
  EXPECT_EQ(buttons, 1U) << "holds the profile's first button";
  EXPECT_GT(largest, 0.005);
  EXPECT_LT(largest, 0.02) << "sweeps 0.01 m around the centre (0)";
  EXPECT_GT(x_pushed[2] - x_free[2], 0.005) << "the effort moves the handle";
  pushed.zero_from_signal_handler();
  EXPECT_EQ(pushed.effort()[2], 0.0);
}

TEST(VendorMaster, ShippedCartesianProfilesMapButtonsByNameAndKeepForcesInTheirLimits) {
  for (const char* name : {"novint-falcon", "force-dimension-omega3", "geomagic-touch"}) {
    const md::MasterProfile p = shipped(name);
    EXPECT_EQ(p.kinematics.type, md::KinematicsType::kIdentity) << name;
    EXPECT_EQ(p.task_axes(), 3U) << name;
    EXPECT_NE(p.description.find("not yet verified on hardware"), std::string::npos) << name;
    const std::string buttons =
        std::string(name) == "geomagic-touch"  ? "{dead_man: dark_grey, clutch: light_grey}"
        : std::string(name) == "novint-falcon" ? "{dead_man: center, clutch: left}"
                                               : "{dead_man: held}";
    const auto cfg = md::parse_mapping(
        YAML::Load("{joints: [{axis: x, scale: 10}, {axis: z, scale: -10}], buttons: " + buttons +
                   "}"),
        p, std::string(name) + " mapping", "");
    md::MasterMapping m(p, cfg);
    md::JointArray x{};
    ASSERT_TRUE(m.update(x, 0x1U)) << name;
    EXPECT_TRUE(m.buttons().dead_man) << name << ": bit 0 or held";
    if (std::string(name) != "force-dimension-omega3") {
      ASSERT_TRUE(m.update(x, 0x3U));
      EXPECT_TRUE(m.buttons().clutch) << name << ": the second button is the clutch";
    }
    // A slave torque far beyond the device: the handle force stays within
    // the profile's limit and keeps its direction.
    md::JointArray tau{};
    tau[0] = 50.0;
    tau[1] = 25.0;
    const md::JointArray f = m.joint_torques(tau);
    EXPECT_NEAR(std::abs(f[0]), p.force_limit[0], 1e-9) << name;
    EXPECT_NEAR(f[2] / f[0], -0.5, 1e-9) << name;
    EXPECT_EQ(f[1], 0.0) << name;
  }
}
