// tsm-devices: what master devices this machine can drive. Subcommands, as
// `tsm` has; the flags they replace stay as aliases.
//   tsm-devices list      (--list)     connected devices matching known profiles, with paths
//   tsm-devices drivers   (--drivers)  registered drivers
//   tsm-devices monitor DRIVER (--monitor DRIVER) [--config FILE] [--seconds S]
//               [--lcm-url URL] [--prefix P]   (driver lcm)
//                                      open a device, print its readings (no torque)
// haptic-server --list-devices prints the same listing (same library call).

#include <yaml-cpp/yaml.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <thread>

#include "files/cli_numbers.hpp"
#include "master_devices/builtin_drivers.hpp"
#include "master_devices/lcm_device.hpp"
#include "master_devices/profile.hpp"
#include "master_devices/profile_dirs.hpp"
#include "master_devices/registry.hpp"
#include "realtime/clock.hpp"
#include "tsmh/cli_words.hpp"
#include "tsmh/version.hpp"

namespace md = tsmh::master_devices;

int main(int argc, char** argv) {
  CLI::App app{"tsm-devices: list and probe tsm-haptics master devices"};
  app.set_version_flag("--version", tsmh::version_line("tsm-devices"));
  bool list = false;
  bool drivers = false;
  std::string monitor;
  std::string config;
  std::string profile_dir = md::default_profiles_dir().string();
  double seconds = 3.0;
  // Subcommands; the options below are the parent's and reach them
  // (fallthrough), so `tsm-devices monitor sim --seconds 1` and
  // `tsm-devices --monitor sim --seconds 1` are the same.
  auto* list_cmd =
      app.add_subcommand("list", "list connected devices that match known profiles")->fallthrough();
  auto* drivers_cmd = app.add_subcommand("drivers", "list registered drivers")->fallthrough();
  auto* monitor_cmd = app.add_subcommand("monitor",
                                         "open a device with the driver DRIVER and print its "
                                         "readings (no torque)")
                          ->fallthrough();
  std::string monitor_driver;
  monitor_cmd->add_option("driver", monitor_driver, "the driver (see `tsm-devices drivers`)")
      ->required();
  app.add_flag("--list", list, "the same as the subcommand list");
  app.add_flag("--drivers", drivers, "the same as the subcommand drivers");
  app.add_option("--monitor", monitor, "the same as the subcommand monitor DRIVER");
  app.add_option("--config", config, "YAML file with the driver's settings map (for monitor)");
  app.add_option("--seconds", seconds, "how long to monitor")
      ->check(tsmh::files::finite_range(0.001, 1e7, "s"));
  std::string lcm_url;
  std::string prefix;
  app.add_option("--lcm-url", lcm_url,
                 "monitor lcm: LCM URL (default: the config's url, else $LCM_DEFAULT_URL)");
  app.add_option("--prefix", prefix,
                 "monitor lcm: channel prefix, e.g. LEFT_ (default: the config's channel_prefix)");
  CLI::Option* profiles_opt =
      app.add_option("--profiles", profile_dir,
                     "directory of device profiles (*.yaml); default: $TSMH_PROFILES_DIR, else "
                     "share/tsm-haptics/profiles next to this program's bin/")
          ->capture_default_str();
  if (const int rc = tsmh::cli_words::check_words(app, argc, argv)) return rc;
  CLI11_PARSE(app, argc, argv);
  list = list || list_cmd->parsed();
  drivers = drivers || drivers_cmd->parsed();
  if (monitor_cmd->parsed()) {
    if (!monitor.empty() && monitor != monitor_driver) {
      std::fprintf(stderr, "tsm-devices: monitor %s and --monitor %s: give one driver\n",
                   monitor_driver.c_str(), monitor.c_str());
      return 2;
    }
    monitor = monitor_driver;
  }

  try {
    md::BuiltinDriverOptions options;
    // A folder named on the command line or in $TSMH_PROFILES_DIR must exist
    // (an error, never a silent fall-back to the built-in profile); the
    // installed default may be absent.
    const char* env_dir = std::getenv(md::kProfilesDirEnv);
    const bool named = profiles_opt->count() > 0 || (env_dir != nullptr && *env_dir != '\0');
    if (named || std::filesystem::is_directory(profile_dir))
      options.profiles = md::load_profiles(profile_dir);
    md::DriverRegistry registry;
    md::register_builtin_drivers(registry, options);
    md::register_lcm_driver(registry);

    if (drivers) {
      for (const auto& [name, description] : registry.drivers()) {
        std::printf("%-10s %s\n", name.c_str(), description.c_str());
      }
    }
    if (list) std::fputs(md::format_connected(registry.list_connected()).c_str(), stdout);
    if (!monitor.empty()) {
      YAML::Node settings;
      md::DriverContext ctx;
      if (!config.empty()) {
        settings = tsmh::config::load_yaml_file(config, "settings");
        ctx.source = config;
        ctx.path = "";
        ctx.base_dir = std::filesystem::path(config).parent_path();
      }
      if (monitor == "lcm") {
        if (!lcm_url.empty()) settings["url"] = lcm_url;
        if (!prefix.empty()) settings["channel_prefix"] = prefix;
      } else if (!lcm_url.empty() || !prefix.empty()) {
        throw std::runtime_error("--lcm-url and --prefix apply to monitor lcm only");
      }
      auto device = registry.create(monitor, settings, ctx);
      device->open();
      const md::DeviceSpec& spec = device->spec();
      std::printf("%s (%s): %u DOF, %.0f Hz\n", spec.model.c_str(), spec.driver.c_str(), spec.dof,
                  spec.nominal_rate_hz);
      const std::int64_t end =
          tsmh::realtime::monotonic_now_ns() + static_cast<std::int64_t>(seconds * 1e9);
      std::int64_t t = tsmh::realtime::monotonic_now_ns();
      while (tsmh::realtime::monotonic_now_ns() < end) {
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
        t = device->simulated_time() ? t + 100'000'000 : tsmh::realtime::monotonic_now_ns();
        const md::DeviceReading r = device->read(t);
        std::printf("%-12s seq %8llu  q", std::string(md::to_string(r.status)).c_str(),
                    static_cast<unsigned long long>(r.sequence));
        for (std::uint32_t j = 0; j < r.dof; ++j)
          std::printf(" %+8.4f", r.q[j]);
        std::printf("  dead-man %d e-stop %d clutch %d  %s\n", r.buttons.dead_man, r.buttons.e_stop,
                    r.buttons.clutch, device->last_error().c_str());
      }
      device->close();
    }
    if (!list && !drivers && monitor.empty()) std::cout << app.help();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "tsm-devices: %s\n", e.what());
    return 1;
  }
  return 0;
}
