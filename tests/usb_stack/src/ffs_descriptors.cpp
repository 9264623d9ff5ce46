#include "ffs_descriptors.hpp"

#include <linux/usb/ch9.h>
#include <linux/usb/functionfs.h>

namespace tsmh::usb_stack {

namespace {

void put8(std::vector<std::uint8_t>& b, unsigned v) {
  b.push_back(static_cast<std::uint8_t>(v));
}
void put16(std::vector<std::uint8_t>& b, unsigned v) {
  put8(b, v & 0xFFU);
  put8(b, (v >> 8) & 0xFFU);
}
void put32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  put16(b, v & 0xFFFFU);
  put16(b, v >> 16);
}
void patch32(std::vector<std::uint8_t>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i)
    b[at + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(v >> (8 * i));
}

constexpr unsigned kMaxPacket = 64;  // every report fits one packet

// Interface + (HID) + two interrupt endpoints; bInterval is in frames at full
// speed (1 = 1 ms) and 2^(n-1) microframes at high speed (4 = 1 ms).
unsigned put_interface(std::vector<std::uint8_t>& b, Personality p, std::size_t report_size,
                       unsigned interval) {
  put8(b, USB_DT_INTERFACE_SIZE);
  put8(b, USB_DT_INTERFACE);
  put8(b, 0);  // bInterfaceNumber (FunctionFS renumbers)
  put8(b, 0);  // bAlternateSetting
  put8(b, 2);  // bNumEndpoints
  put8(b, p == Personality::kHid ? USB_CLASS_HID : USB_CLASS_VENDOR_SPEC);
  put8(b, 0);  // bInterfaceSubClass: no boot protocol
  put8(b, 0);  // bInterfaceProtocol
  put8(b, 1);  // iInterface: our first string
  unsigned count = 1;
  if (p == Personality::kHid) {
    const auto hid = hid_class_descriptor(report_size);
    b.insert(b.end(), hid.begin(), hid.end());
    ++count;
  }
  for (unsigned address : {1U | USB_DIR_IN, 2U | USB_DIR_OUT}) {
    put8(b, USB_DT_ENDPOINT_SIZE);
    put8(b, USB_DT_ENDPOINT);
    put8(b, address);
    put8(b, USB_ENDPOINT_XFER_INT);
    put16(b, kMaxPacket);
    put8(b, interval);
    ++count;
  }
  return count;
}

}  // namespace

std::vector<std::uint8_t> hid_class_descriptor(std::size_t report_descriptor_size) {
  std::vector<std::uint8_t> b;
  put8(b, 9);
  put8(b, kHidDescriptorType);
  put16(b, 0x0111);  // bcdHID 1.11
  put8(b, 0);        // bCountryCode
  put8(b, 1);        // bNumDescriptors
  put8(b, kHidReportDescriptorType);
  put16(b, static_cast<unsigned>(report_descriptor_size));
  return b;
}

std::vector<std::uint8_t> ffs_descriptors(Personality p,
                                          std::span<const std::uint8_t> report_descriptor) {
  std::vector<std::uint8_t> b;
  put32(b, FUNCTIONFS_DESCRIPTORS_MAGIC_V2);
  put32(b, 0);  // length, patched below
  put32(b, FUNCTIONFS_HAS_FS_DESC | FUNCTIONFS_HAS_HS_DESC);
  const std::size_t counts_at = b.size();
  put32(b, 0);  // fs_count
  put32(b, 0);  // hs_count
  patch32(b, counts_at, put_interface(b, p, report_descriptor.size(), 1));
  patch32(b, counts_at + 4, put_interface(b, p, report_descriptor.size(), 4));
  patch32(b, 4, static_cast<std::uint32_t>(b.size()));
  return b;
}

std::vector<std::uint8_t> ffs_strings(std::string_view interface_name) {
  std::vector<std::uint8_t> b;
  put32(b, FUNCTIONFS_STRINGS_MAGIC);
  put32(b, 0);  // length, patched below
  put32(b, 1);  // str_count
  put32(b, 1);  // lang_count
  put16(b, 0x0409);
  b.insert(b.end(), interface_name.begin(), interface_name.end());
  put8(b, 0);
  patch32(b, 4, static_cast<std::uint32_t>(b.size()));
  return b;
}

}  // namespace tsmh::usb_stack
