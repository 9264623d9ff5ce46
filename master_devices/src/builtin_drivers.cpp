#include "master_devices/builtin_drivers.hpp"

#include <cmath>
#include <numbers>

#include "master_devices/console_device.hpp"
#include "master_devices/emulator_bus.hpp"
#include "master_devices/haply_device.hpp"
#include "master_devices/hidapi_transport.hpp"
#include "master_devices/libusb_transport.hpp"
#include "master_devices/sim_device.hpp"

namespace tsmh::master_devices {

namespace {

std::vector<ConnectedDevice> list_with(TransportProvider& provider, const std::string& driver,
                                       const std::vector<DeviceProfile>& profiles) {
  std::vector<ConnectedDevice> out;
  for (const DeviceProfile& p : profiles) {
    for (const TransportDeviceInfo& d : provider.enumerate(p.vendor_id, p.product_id)) {
      out.push_back(
          ConnectedDevice{driver, d.path, d.vendor_id, d.product_id, d.serial, d.product, p.name});
    }
  }
  return out;
}

std::shared_ptr<EmulatorBus> make_emulator(config::FieldReader& r, const DeviceProfile& profile,
                                           std::shared_ptr<const Clock> clock) {
  EmulatorBus::Options options;
  options.clock = std::move(clock);
  options.firmware = firmware_for_profile(profile);
  options.vendor_id = profile.vendor_id;
  options.product_id = profile.product_id;
  options.path = "emu:0";
  const YAML::Node op = r.node("operator");
  if (op.IsDefined()) {
    // A simulated hand on the emulated handle: the mechanism carries the
    // hand's inertia, the hand pushes with its arm impedance.
    config::FieldReader o(op, r.source(), r.field("operator"));
    const std::size_t dof = profile.joints.size();
    Scenario scenario = parse_scenario(o, dof);
    HandParams hand;
    config::FieldReader h(o.node("hand"), o.source(), o.field("hand"));
    hand.inertia_kgm2 = h.get_double("inertia_kgm2", hand.inertia_kgm2);
    hand.stiffness_nm_per_rad = h.get_double("stiffness_nm_per_rad", hand.stiffness_nm_per_rad);
    hand.damping_nms_per_rad = h.get_double("damping_nms_per_rad", hand.damping_nms_per_rad);
    if (!(hand.inertia_kgm2 > 0)) h.fail("inertia_kgm2", "must be > 0");
    if (!(hand.stiffness_nm_per_rad > 0)) h.fail("stiffness_nm_per_rad", "must be > 0");
    if (!(hand.damping_nms_per_rad >= 0)) h.fail("damping_nms_per_rad", "must be >= 0");
    h.reject_unknown();
    const Buttons buttons{o.get_bool("dead_man", true), false, false};
    o.reject_unknown();
    for (std::size_t j = 0; j < dof; ++j)
      options.firmware.joints[j].inertia_kgm2 += hand.inertia_kgm2;
    auto t = std::make_shared<double>(0.0);
    options.world = [scenario, hand, t, dof, buttons](Firmware& fw, std::int64_t dt_ns) {
      *t += static_cast<double>(dt_ns) * 1e-9;
      fw.set_buttons(buttons);
      const Intention in = intention_at(scenario, *t, dof);
      // The mechanism frame is the joint frame (the profile's direction and
      // zero offset undo the mounting), so the hand acts on it directly.
      for (std::size_t j = 0; j < dof; ++j) {
        const double tau = hand.stiffness_nm_per_rad * (in.q[j] - fw.position_rad(j)) +
                           hand.damping_nms_per_rad * (in.qd[j] - fw.velocity_rad_s(j));
        fw.set_external_torque(j, tau);
      }
    };
  }
  return std::make_shared<EmulatorBus>(std::move(options));
}

}  // namespace

FirmwareConfig firmware_for_profile(const DeviceProfile& profile) {
  FirmwareConfig c = default_console_firmware();
  const std::size_t dof = std::min(profile.joints.size(), protocol::kJoints);
  c.info.dof = static_cast<std::uint8_t>(dof);
  c.info.nominal_rate_hz =
      static_cast<std::uint16_t>(std::lround(std::clamp(profile.nominal_rate_hz, 1.0, 65535.0)));
  c.info.default_watchdog_ms = profile.watchdog_ms;
  for (std::size_t j = 0; j < protocol::kJoints; ++j) {
    if (j >= dof) {
      c.info.counts_per_rev[j] = 0;
      c.info.max_current_ma[j] = 0;
      continue;
    }
    const JointProfile& jp = profile.joints[j];
    c.info.counts_per_rev[j] =
        static_cast<std::uint32_t>(std::lround(jp.counts_per_rad * 2.0 * std::numbers::pi));
    c.info.max_current_ma[j] = static_cast<std::uint16_t>(std::min<long>(
        protocol::kMaxCurrentMa, std::lround(std::ceil(jp.current_limit_peak_a * 1000.0))));
    c.encoder_offset_counts[j] = jp.zero_offset_counts;
    c.mount_direction[j] = static_cast<std::int8_t>(jp.direction);
    c.joints[j].torque_constant_nm_per_a = jp.torque_constant_nm_per_a;
    c.joints[j].position_min_rad = jp.position_min_rad - 0.1;
    c.joints[j].position_max_rad = jp.position_max_rad + 0.1;
  }
  return c;
}

DeviceProfile select_profile(config::FieldReader& r, const std::vector<DeviceProfile>& known,
                             const DriverContext& context) {
  if (!r.has("profile")) {
    r.node("profile");
    return known.front();
  }
  const std::string value = r.get_string("profile");
  for (const DeviceProfile& p : known) {
    if (p.name == value) return p;
  }
  const bool looks_like_file =
      value.find('/') != std::string::npos ||
      (value.size() > 5 && value.compare(value.size() - 5, 5, ".yaml") == 0);
  if (!looks_like_file) {
    std::string names;
    for (const DeviceProfile& p : known)
      names += (names.empty() ? "" : ", ") + p.name;
    r.fail("profile",
           "unknown profile '" + value + "' (known: " + names + "; or give a .yaml file)");
  }
  std::filesystem::path file(value);
  if (file.is_relative() && !context.base_dir.empty()) file = context.base_dir / file;
  return load_profile(file);
}

void register_builtin_drivers(DriverRegistry& registry, BuiltinDriverOptions options) {
  auto profiles = std::make_shared<std::vector<DeviceProfile>>(std::move(options.profiles));
  if (profiles->empty()) profiles->push_back(builtin_console_profile());
  const std::shared_ptr<const Clock> clock = options.clock ? options.clock : monotonic_clock();

  auto console_factory = [profiles, clock](const std::string& driver,
                                           std::function<std::shared_ptr<TransportProvider>(
                                               config::FieldReader&, const DeviceProfile&)>
                                               make_provider) {
    return [profiles, clock, driver, make_provider](const YAML::Node& settings,
                                                    const DriverContext& ctx) {
      config::FieldReader r(settings, ctx.source, ctx.path);
      DeviceProfile profile = select_profile(r, *profiles, ctx);
      ConsoleSettings cs = parse_console_settings(r);
      std::shared_ptr<TransportProvider> provider = make_provider(r, profile);
      r.reject_unknown();
      return std::unique_ptr<Device>(std::make_unique<ConsoleDevice>(
          driver, std::move(profile), std::move(cs), std::move(provider), clock));
    };
  };

  registry.add("hid", "our 2-DOF console over hidapi (hidraw), protocol in docs/hid-protocol.md",
               console_factory("hid",
                               [clock](config::FieldReader& r, const DeviceProfile&) {
                                 HidapiProvider::Options o;
                                 o.clock = clock;
                                 o.read_timeout_ms = static_cast<int>(
                                     r.get_int("read_timeout_ms", o.read_timeout_ms));
                                 if (o.read_timeout_ms < 1)
                                   r.fail("read_timeout_ms", "must be >= 1");
                                 return std::make_shared<HidapiProvider>(o);
                               }),
               [profiles] {
                 HidapiProvider provider;
                 return list_with(provider, "hid", *profiles);
               });

  registry.add("usb", "our 2-DOF console over libusb (vendor interface, async transfers, hotplug)",
               console_factory("usb",
                               [clock](config::FieldReader& r, const DeviceProfile&) {
                                 LibusbProvider::Options o;
                                 o.clock = clock;
                                 o.in_transfers =
                                     static_cast<int>(r.get_int("in_transfers", o.in_transfers));
                                 if (o.in_transfers < 1 || o.in_transfers > 32)
                                   r.fail("in_transfers", "must be 1 .. 32");
                                 // Consoles libusb does not list (no udevd) from sysfs.
                                 if (!r.get_bool("sysfs_fallback", true)) o.sysfs_root.clear();
                                 return std::make_shared<LibusbProvider>(o);
                               }),
               [profiles] {
                 LibusbProvider provider;
                 return list_with(provider, "usb", *profiles);
               });

  registry.add(
      "emulator", "our console's firmware emulated in-process, through the hid/usb driver code",
      console_factory("emulator", [clock](config::FieldReader& r, const DeviceProfile& profile) {
        return std::static_pointer_cast<TransportProvider>(make_emulator(r, profile, clock));
      }));

  registry.add("sim",
               "simulated master with an operator hand model (scenarios palpate, sine, step)",
               [clock](const YAML::Node& settings, const DriverContext& ctx) {
                 config::FieldReader r(settings, ctx.source, ctx.path);
                 SimSettings s = parse_sim_settings(r);
                 r.reject_unknown();
                 return std::unique_ptr<Device>(std::make_unique<SimDevice>(std::move(s), clock));
               });
  register_haply_driver(registry, clock);
}

}  // namespace tsmh::master_devices
