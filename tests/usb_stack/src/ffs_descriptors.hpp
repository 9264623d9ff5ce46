#pragma once
// The USB descriptors a FunctionFS console writes to ep0: one interface with
// an interrupt IN endpoint (ep1, input reports) and an interrupt OUT
// endpoint (ep2, output reports), polled every millisecond at full and high
// speed. Two personalities:
// - kHid: interface class HID with a HID class descriptor, so the host's
//   usbhid binds and hidraw (hidapi) sees the console. Unlike usb_f_hid,
//   FunctionFS hands GET_REPORT/SET_REPORT(Feature) to userspace, so the
//   firmware answers them as real hardware does.
// - kVendor: vendor-specific class (0xFF): no kernel driver binds; the host
//   reaches it with libusb.

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace tsmh::usb_stack {

enum class Personality { kHid, kVendor };

inline constexpr std::uint8_t kHidDescriptorType = 0x21;
inline constexpr std::uint8_t kHidReportDescriptorType = 0x22;

/// The FunctionFS v2 descriptor blob (full- and high-speed sets).
/// `report_descriptor` sizes the HID class descriptor (kHid only).
std::vector<std::uint8_t> ffs_descriptors(Personality p,
                                          std::span<const std::uint8_t> report_descriptor);

/// The HID class descriptor (9 bytes) announcing a report descriptor of this size.
std::vector<std::uint8_t> hid_class_descriptor(std::size_t report_descriptor_size);

/// The FunctionFS strings blob: one US-English string, the interface name.
std::vector<std::uint8_t> ffs_strings(std::string_view interface_name);

}  // namespace tsmh::usb_stack
