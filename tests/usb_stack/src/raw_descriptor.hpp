#pragma once
// The stand-in console used by the raw kernel-semantics cases: a vendor-page
// HID descriptor with numbered reports shaped like the real protocol's
// (input ID 1, output ID 2, feature ID 3). It exercises what the kernel does
// with report IDs independently of our codec.

#include <array>
#include <cstddef>
#include <cstdint>

namespace tsmh::usb_stack::raw {

inline constexpr std::uint8_t kInputId = 1;
inline constexpr std::uint8_t kOutputId = 2;
inline constexpr std::uint8_t kFeatureId = 3;
inline constexpr std::size_t kPayload = 8;                  ///< bytes after the report ID
inline constexpr std::size_t kReportLength = kPayload + 1;  ///< with the ID byte

// clang-format off
inline constexpr std::array<std::uint8_t, 39> kReportDescriptor = {
    0x06, 0x00, 0xFF,  // Usage Page (Vendor 0xFF00)
    0x09, 0x01,        // Usage (1)
    0xA1, 0x01,        // Collection (Application)
    0x15, 0x00,        //   Logical Minimum (0)
    0x26, 0xFF, 0x00,  //   Logical Maximum (255)
    0x75, 0x08,        //   Report Size (8)
    0x85, kInputId,    //   Report ID (1)
    0x95, kPayload,    //   Report Count (8)
    0x09, 0x02,        //   Usage (2)
    0x81, 0x02,        //   Input (Data, Var, Abs)
    0x85, kOutputId,   //   Report ID (2)
    0x95, kPayload,    //   Report Count (8)
    0x09, 0x03,        //   Usage (3)
    0x91, 0x02,        //   Output (Data, Var, Abs)
    0x85, kFeatureId,  //   Report ID (3)
    0x95, kPayload,    //   Report Count (8)
    0x09, 0x04,        //   Usage (4)
    0xB1, 0x02,        //   Feature (Data, Var, Abs)
    0xC0,              // End Collection
};
// clang-format on

/// The device's answer to output payload byte b: b + 1 (mod 256), so a reply
/// proves the device saw this exact report, not a stale one.
inline std::uint8_t echo(std::uint8_t b) {
  return static_cast<std::uint8_t>(b + 1);
}

}  // namespace tsmh::usb_stack::raw
