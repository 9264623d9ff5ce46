// The real transports without hardware: they must enumerate nothing and
// fail to open with messages that say what to do, never crash. Their data
// paths run against a real kernel in the QEMU USB-gadget tests.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "master_devices/hidapi_transport.hpp"
#include "master_devices/libusb_transport.hpp"

namespace tsmh::master_devices {
namespace {

TEST(HidapiTransport, EnumeratesNothingHereAndOpenNamesThePath) {
  HidapiProvider hid;
  EXPECT_EQ(hid.name(), "hidapi");
  EXPECT_TRUE(hid.enumerate(0x1209, 0x0001).empty());
  try {
    hid.open(TransportDeviceInfo{"/dev/hidraw-nope", 0x1209, 0x0001, "", "", ""});
    FAIL();
  } catch (const TransportError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("/dev/hidraw-nope"), std::string::npos) << what;
    EXPECT_NE(what.find("udev rules"), std::string::npos) << what;
  }
}

TEST(HidapiTransport, WideStringsBecomeUtf8) {
  EXPECT_EQ(utf8_from_wide(nullptr), "");
  EXPECT_EQ(utf8_from_wide(L"console"), "console");
  EXPECT_EQ(utf8_from_wide(L"\u00e9\u20ac\U0001F600"), "\xC3\xA9\xE2\x82\xAC\xF0\x9F\x98\x80");
}

TEST(LibusbTransport, EnumeratesNothingHereAndOpenFailsCleanly) {
  LibusbProvider usb;
  EXPECT_EQ(usb.name(), "libusb");
  EXPECT_TRUE(usb.enumerate(0x1209, 0x0001).empty());
  EXPECT_THROW(usb.open(TransportDeviceInfo{"usb:9-9", 0x1209, 0x0001, "", "", ""}),
               TransportError);
  usb.set_arrival_callback([] {});
  usb.set_arrival_callback({});
}

TEST(LibusbTransport, PortPathsLookLikeSysfs) {
  const std::uint8_t ports[] = {4, 2, 1};
  EXPECT_EQ(usb_port_path(1, ports, 3), "usb:1-4.2.1");
  EXPECT_EQ(usb_port_path(3, ports, 1), "usb:3-4");
}

// A fake /sys/bus/usb/devices: what the kernel shows without any udev.
class FakeSysfs {
 public:
  FakeSysfs()
      : root_(std::filesystem::temp_directory_path() /
              ("tsmh_fake_sysfs_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(root_);
    device("1-1", {{"idVendor", "1209"},
                   {"idProduct", "0001"},
                   {"busnum", "1"},
                   {"devnum", "7"},
                   {"serial", "usb-stack-0001"},
                   {"manufacturer", "tsm-haptics test"},
                   {"product", "tsm-haptics console"}});
    device("1-1:1.0", {{"bInterfaceClass", "ff"}});  // an interface, not a device
    device("usb1", {{"idVendor", "1d6b"},
                    {"idProduct", "0002"},
                    {"busnum", "1"},
                    {"devnum", "1"}});  // the root hub
    device("2-3.1", {{"idVendor", "046d"},
                     {"idProduct", "c52b"},
                     {"busnum", "2"},
                     {"devnum", "4"}});  // someone else's device
    device("2-4", {{"idVendor", "1209"}, {"idProduct", "0001"}, {"busnum", "2"}});  // going away
    device("3-2", {{"idVendor", "1209"},
                   {"idProduct", "0001"},
                   {"busnum", "3"},
                   {"devnum", "12"}});  // a console without strings
  }
  ~FakeSysfs() { std::filesystem::remove_all(root_); }
  std::string root() const { return root_.string(); }

 private:
  void device(const std::string& name, const std::map<std::string, std::string>& attributes) {
    std::filesystem::create_directories(root_ / name);
    for (const auto& [key, value] : attributes)
      std::ofstream(root_ / name / key) << value << "\n";
  }
  std::filesystem::path root_;
};

TEST(LibusbTransport, ScansSysfsForConsolesWithoutUdev) {
  FakeSysfs sysfs;
  const std::vector<SysfsUsbDevice> found = scan_sysfs_usb(sysfs.root(), 0x1209, 0x0001);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].name, "1-1");
  EXPECT_EQ(found[0].busnum, 1);
  EXPECT_EQ(found[0].devnum, 7);
  EXPECT_EQ(found[0].serial, "usb-stack-0001");
  EXPECT_EQ(found[0].product, "tsm-haptics console");
  EXPECT_EQ(found[1].name, "3-2");
  EXPECT_EQ(found[1].serial, "");
  EXPECT_TRUE(scan_sysfs_usb(sysfs.root() + "/nope", 0x1209, 0x0001).empty());
}

TEST(LibusbTransport, ListsWhatSysfsHasAndOpensItThroughItsUsbfsNode) {
  FakeSysfs sysfs;
  LibusbProvider::Options o;
  o.sysfs_root = sysfs.root();
  o.usbfs_root = sysfs.root() + "/no-usbfs";
  LibusbProvider usb(o);
  const std::vector<TransportDeviceInfo> listed = usb.enumerate(0x1209, 0x0001);
  ASSERT_EQ(listed.size(), 2u) << "libusb lists none here; sysfs has two";
  EXPECT_EQ(listed[0].path, "usb:1-1");
  EXPECT_EQ(listed[0].serial, "usb-stack-0001");
  EXPECT_EQ(listed[0].manufacturer, "tsm-haptics test");
  EXPECT_EQ(listed[1].path, "usb:3-2");
  // Not known to libusb: opened through <usbfs_root>/BBB/DDD, which is missing here.
  try {
    usb.open(listed[0]);
    FAIL();
  } catch (const TransportError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("usb:1-1: opening " + o.usbfs_root + "/001/007"), std::string::npos)
        << what;
  }
  EXPECT_EQ(usb.fallback_opens(), 0u);
  // Without the fallback only libusb's own (empty) list counts.
  LibusbProvider::Options off = o;
  off.sysfs_root.clear();
  EXPECT_TRUE(LibusbProvider(off).enumerate(0x1209, 0x0001).empty());
}

}  // namespace
}  // namespace tsmh::master_devices
