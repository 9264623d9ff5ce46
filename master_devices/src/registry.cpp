#include "master_devices/registry.hpp"

#include <cstdio>
#include <stdexcept>

#include "config/field_reader.hpp"

namespace tsmh::master_devices {

void DriverRegistry::add(std::string name, std::string description, Factory factory,
                         Lister lister) {
  if (name.empty()) throw std::invalid_argument("driver name must not be empty");
  if (!factory) throw std::invalid_argument("driver '" + name + "' needs a factory");
  const auto [it, inserted] =
      entries_.emplace(name, Entry{std::move(description), std::move(factory), std::move(lister)});
  (void)it;
  if (!inserted) throw std::invalid_argument("driver '" + name + "' is already registered");
}

bool DriverRegistry::has(std::string_view name) const {
  return entries_.find(name) != entries_.end();
}

std::unique_ptr<Device> DriverRegistry::create(std::string_view name, const YAML::Node& settings,
                                               const DriverContext& context) const {
  const auto it = entries_.find(name);
  if (it == entries_.end()) {
    std::string known;
    for (const auto& [n, e] : entries_)
      known += (known.empty() ? "" : ", ") + n;
    throw config::ConfigError(context.source + ": unknown device driver '" + std::string(name) +
                              "' (registered: " + known + ")");
  }
  return it->second.factory(settings, context);
}

std::vector<std::pair<std::string, std::string>> DriverRegistry::drivers() const {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& [n, e] : entries_)
    out.emplace_back(n, e.description);
  return out;
}

std::vector<ConnectedDevice> DriverRegistry::list_connected() const {
  std::vector<ConnectedDevice> out;
  for (const auto& [n, e] : entries_) {
    if (!e.lister) continue;
    try {
      for (auto& d : e.lister())
        out.push_back(std::move(d));
    } catch (const std::exception&) {
      // One transport failing to enumerate (e.g. no usbfs in a container)
      // must not hide devices the others see.
    }
  }
  return out;
}

std::unique_ptr<Device> create_device(const DriverRegistry& registry, const YAML::Node& device_node,
                                      const DriverContext& context) {
  config::FieldReader r(device_node, context.source, context.path);
  const std::string driver = r.get_string("driver");
  const YAML::Node settings = r.node("settings");
  r.reject_unknown();
  DriverContext ctx = context;
  ctx.path = r.field("settings");
  return registry.create(driver, settings, ctx);
}

}  // namespace tsmh::master_devices

namespace tsmh::master_devices {

std::string format_connected(const std::vector<ConnectedDevice>& devices) {
  if (devices.empty()) return "no known master devices connected\n";
  std::string out;
  for (const ConnectedDevice& d : devices) {
    char id[16];
    std::snprintf(id, sizeof id, "%04x:%04x", d.vendor_id, d.product_id);
    out += d.driver + "\t" + d.path + "\t" + id + "\tprofile=" + d.profile;
    if (!d.serial.empty()) out += "\tserial=" + d.serial;
    if (!d.product.empty()) out += "\t\"" + d.product + "\"";
    out += "\n";
  }
  return out;
}

}  // namespace tsmh::master_devices
