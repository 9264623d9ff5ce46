// The real transports without hardware: they must enumerate nothing and
// fail to open with messages that say what to do, never crash. Their data
// paths run against a real kernel in the QEMU USB-gadget tests (issue 9).

#include <gtest/gtest.h>

#include <cstdint>

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

}  // namespace
}  // namespace tsmh::master_devices
