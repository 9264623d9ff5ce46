#pragma once
// libusb-1.0 transport for the console's vendor-class interface: the same
// reports as over HID, on an interrupt IN/OUT endpoint pair, with features
// as vendor control requests (docs/hid-protocol.md, "USB vendor interface").
// Asynchronous transfers (several IN transfers in flight, so no
// microframe is missed at high-speed rates of up to 8 kHz) complete on one
// event thread per provider, which also receives hotplug arrive/leave.
//
// libusb's device list (Linux, Debian's udev build) is kept up to date only by
// udevd's announcements: without udevd (a container, an initramfs) a console
// plugged in after libusb_init() never appears in it, and no hotplug event
// comes. So enumerate() also scans sysfs, which the kernel keeps itself, and
// open() opens a console libusb does not know through its usbfs node
// (libusb_wrap_sys_device). The driver's periodic reconnect poll then finds a
// replugged console with or without udevd.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "master_devices/clock.hpp"
#include "master_devices/transport.hpp"

namespace tsmh::master_devices {

class LibusbProvider final : public TransportProvider {
 public:
  struct Options {
    int interface_class = 0xFF;  ///< the vendor-specific interface carrying the protocol
    unsigned control_timeout_ms = 500;
    int in_transfers = 4;  ///< IN transfers kept in flight
    /// Where the kernel lists USB devices ("" disables the sysfs fallback).
    std::string sysfs_root = "/sys/bus/usb/devices";
    /// usbfs device nodes, <root>/BBB/DDD.
    std::string usbfs_root = "/dev/bus/usb";
    /// Stamps each input report's arrival (the driver's clock).
    std::shared_ptr<const Clock> clock = monotonic_clock();
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
  /// How many opens went through the sysfs fallback (libusb did not list the device).
  std::uint64_t fallback_opens() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// The path we give a USB device: "usb:<bus>-<port>[.<port>...]" (as in sysfs).
std::string usb_port_path(int bus, const std::uint8_t* ports, int count);

/// A USB device as sysfs describes it: no udev, no libusb, no opening needed.
struct SysfsUsbDevice {
  std::string name;  ///< the sysfs directory, "1-4.2"; our path is "usb:" + name
  int busnum = 0;
  int devnum = 0;
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial;
  std::string manufacturer;
  std::string product;
};

/// The devices under `root` (normally /sys/bus/usb/devices) with this
/// VID/PID; empty when the directory cannot be read. Root hubs ("usb1") and
/// interfaces ("1-1:1.0") are skipped, and so is an entry whose attributes
/// cannot be read or parsed (a device going away).
std::vector<SysfsUsbDevice> scan_sysfs_usb(const std::string& root, std::uint16_t vendor_id,
                                           std::uint16_t product_id);

}  // namespace tsmh::master_devices
