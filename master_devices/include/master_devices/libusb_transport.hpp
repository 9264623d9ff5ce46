#pragma once
// libusb-1.0 transport for the console's vendor-class interface: the same
// reports as over HID, on an interrupt IN/OUT endpoint pair, with features
// as vendor control requests (docs/hid-protocol.md, "USB vendor interface").
// Asynchronous transfers (several IN transfers in flight, so no
// microframe is missed at high-speed rates of up to 8 kHz) complete on one
// event thread per provider, which also receives hotplug arrive/leave.

#include <memory>
#include <string>

#include "master_devices/transport.hpp"

namespace tsmh::master_devices {

class LibusbProvider final : public TransportProvider {
 public:
  struct Options {
    int interface_class = 0xFF;  ///< the vendor-specific interface carrying the protocol
    unsigned control_timeout_ms = 500;
    int in_transfers = 4;  ///< IN transfers kept in flight
  };
  LibusbProvider();
  explicit LibusbProvider(Options options);
  ~LibusbProvider() override;

  std::string_view name() const override { return "libusb"; }
  std::vector<TransportDeviceInfo> enumerate(std::uint16_t vendor_id,
                                             std::uint16_t product_id) override;
  std::unique_ptr<Transport> open(const TransportDeviceInfo& device) override;
  void set_arrival_callback(std::function<void()> callback) override;

  /// Why libusb is unusable on this machine ("" when it initialised).
  const std::string& init_error() const;
  /// Whether this libusb build delivers hotplug events.
  bool hotplug_supported() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// The path we give a USB device: "usb:<bus>-<port>[.<port>...]" (as in sysfs).
std::string usb_port_path(int bus, const std::uint8_t* ports, int count);

}  // namespace tsmh::master_devices
