#pragma once
// The drivers of this library, for a DriverRegistry:
//
//   hid       our console over hidapi/hidraw          (lists connected devices)
//   usb       our console over libusb, vendor class   (lists connected devices)
//   emulator  our console's firmware emulated in-process, driven by the same
//             driver code as hid/usb; optionally with a simulated operator
//   sim       a simulated master with an operator hand model (the demo's)
//   haply     Haply's 2DIY over its USB serial board (haply_device.hpp)
//
// The lcm driver lives in the master_devices_lcm target (lcm_device.hpp).

#include <memory>
#include <vector>

#include "master_devices/clock.hpp"
#include "master_devices/firmware.hpp"
#include "master_devices/profile.hpp"
#include "master_devices/registry.hpp"

namespace tsmh::master_devices {

struct BuiltinDriverOptions {
  /// Profiles the console drivers know: what `profile: NAME` may name and
  /// what --list-devices matches against. Empty: builtin_console_profile().
  std::vector<DeviceProfile> profiles;
  /// The host clock every device (and its transport) reads; a test may give
  /// a ManualClock. The emulator's and sim's real-time threads are still
  /// paced on CLOCK_MONOTONIC.
  std::shared_ptr<const Clock> clock = monotonic_clock();
};

void register_builtin_drivers(DriverRegistry& registry, BuiltinDriverOptions options = {});

/// Firmware emulating a console that the profile describes exactly (same
/// counts, limits, rate, zero offset and direction).
FirmwareConfig firmware_for_profile(const DeviceProfile& profile);

/// The profile a console driver's settings select: `profile: NAME` of a
/// known profile, `profile: FILE.yaml` (relative to the context's base_dir),
/// or the first known profile when absent.
DeviceProfile select_profile(config::FieldReader& settings, const std::vector<DeviceProfile>& known,
                             const DriverContext& context);

}  // namespace tsmh::master_devices
