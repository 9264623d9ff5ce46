#pragma once
// Drivers registered at run time by name. The server config picks one:
//
//   device:
//     driver: hid          # a registered name
//     settings: {...}      # that driver's own settings
//
// No globals and no static self-registration: whoever builds the registry
// (the server, a test, a tool) decides which drivers exist, e.g. with
// register_builtin_drivers() and, from the lcm target, register_lcm_driver().

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "master_devices/device.hpp"

namespace tsmh::master_devices {

/// Where a driver's settings come from, for error messages and relative paths.
struct DriverContext {
  std::string source = "settings";  ///< file name, e.g. "server.yaml"
  std::string path = "settings";    ///< where the settings map sits, e.g. "device.settings"
  std::filesystem::path base_dir;   ///< relative paths in the settings resolve here
};

/// A device that is plugged in and matches a known profile.
struct ConnectedDevice {
  std::string driver;  ///< driver that can open it ("hid", "usb")
  std::string path;    ///< what to put in the driver's `path` setting
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial;
  std::string product;
  std::string profile;  ///< name of the matching profile
};

class DriverRegistry {
 public:
  using Factory = std::function<std::unique_ptr<Device>(const YAML::Node& settings,
                                                        const DriverContext& context)>;
  using Lister = std::function<std::vector<ConnectedDevice>()>;

  /// Adds a driver. Throws std::invalid_argument when the name is taken or empty.
  void add(std::string name, std::string description, Factory factory, Lister lister = {});
  bool has(std::string_view name) const;
  /// Creates (does not open) a device. Throws config::ConfigError for an unknown
  /// driver (naming the known ones) or bad settings.
  std::unique_ptr<Device> create(std::string_view name, const YAML::Node& settings,
                                 const DriverContext& context = {}) const;
  /// Registered drivers: name and one-line description, sorted by name.
  std::vector<std::pair<std::string, std::string>> drivers() const;
  /// Connected devices from every driver that can list them. Errors of one
  /// driver's enumeration do not hide the others' devices.
  std::vector<ConnectedDevice> list_connected() const;

 private:
  struct Entry {
    std::string description;
    Factory factory;
    Lister lister;
  };
  std::map<std::string, Entry, std::less<>> entries_;
};

/// Creates a device from a config node of the form {driver: NAME, settings: {...}}.
/// Here `context.path` is where that node sits (e.g. "device"; "" at the root).
std::unique_ptr<Device> create_device(const DriverRegistry& registry, const YAML::Node& device_node,
                                      const DriverContext& context);

}  // namespace tsmh::master_devices

namespace tsmh::master_devices {

/// The device listing as `tsm-devices --list` and `haptic-server
/// --list-devices` print it: one line per device, or a line saying none.
std::string format_connected(const std::vector<ConnectedDevice>& devices);

}  // namespace tsmh::master_devices
