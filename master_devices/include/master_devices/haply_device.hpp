#pragma once
// The `haply` driver: Haply's 2DIY, a two-DOF pantograph whose board speaks a
// small binary protocol over USB serial (CDC-ACM, /dev/ttyACM*;
// haply_protocol.hpp). Not yet verified on hardware.
//
// The device itself reads the two motor angles (rad, hAPI's convention:
// kinematics.hpp's pantograph) and takes two motor torques (N m). With a
// `mapping:` in its settings the registry wraps it in a MappedDevice
// (mapped_device.hpp), so haptic-server sees the slave's joints: the handle's
// position through the pantograph's kinematics, the force back through its
// Jacobian transpose, within the profile's limits.
//
// Its I/O thread asks the board for a sample (a state command carrying the
// torque) once per period and waits for the reply. Host-side watchdog: when
// the board has not answered for `watchdog_ms`, read() says DISCONNECTED
// (stale) and every command goes out with zero torque until it answers again
// (the board's firmware has no watchdog of its own: it keeps the last torque
// it was given). Unplugged (the port reports a hang-up or I/O error): FAULT
// (kLinkLost), a last_error() that says so, zero torque; clear_fault()
// reopens the port and repeats the handshake, and fails while the board is
// absent.

#include <atomic>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "master_devices/clock.hpp"
#include "master_devices/driver_base.hpp"
#include "master_devices/haply_protocol.hpp"
#include "master_devices/master_profile.hpp"
#include "master_devices/registry.hpp"
#include "master_devices/serial_port.hpp"
#include "realtime/latest_value.hpp"

namespace tsmh::master_devices {

struct HaplySettings {
  std::string port;                  ///< e.g. /dev/ttyACM0 (required)
  MasterProfile profile;             ///< kinematics, limits, rate
  haply::BoardConfig board;          ///< the board's wiring (a preset or the profile's default)
  double rate_hz = 1000.0;           ///< requests per second (default: the profile's rate)
  double watchdog_ms = 20.0;         ///< no reply this long: stale, zero torque
  double command_timeout_ms = 20.0;  ///< no write_torque() this long: zero torque
  double open_timeout_ms = 3000.0;   ///< the handshake's limit (a board may boot on open)
  int max_bad_replies = 10;          ///< consecutive malformed replies before FAULT
  /// FAULT (kWorkspace; at open: refused) when the handle is this far outside
  /// the profile's workspace: a wrong board preset or a handle that was not
  /// at rest when the board was set up (its encoders count from there).
  double workspace_margin_m = 0.05;
};

/// Reads the driver's settings (port, profile, board, rate_hz, watchdog_ms,
/// command_timeout_ms, open_timeout_ms, max_bad_replies, workspace_margin_m); does not call
/// reject_unknown() (the factory also reads `mapping`).
HaplySettings parse_haply_settings(config::FieldReader& r, const DriverContext& context);

/// The built-in master profiles of the 2DIY (`haply-2diy`: third-generation
/// geometry and board; `haply-2diy-gen2`), the same text as
/// master_devices/profiles/masters/<name>.yaml.
MasterProfile builtin_haply_profile(std::string_view name);
std::string_view builtin_haply_profile_text(std::string_view name);

class HaplyDevice final : public DriverBase {
 public:
  explicit HaplyDevice(HaplySettings s, std::shared_ptr<const Clock> clock = monotonic_clock());
  ~HaplyDevice() override;

  /// Opens the port, resets and sets up the board, and waits for its first
  /// reply; throws DeviceError naming the port and the cause.
  void open() override;
  /// Sends zero torque (and waits briefly for the board to take it), then
  /// releases the port.
  void close() noexcept override;
  bool clear_fault() override;
  /// Readings older than watchdog_ms are stale.
  std::int64_t freshness_bound_ns() const noexcept override;

  const HaplySettings& settings() const { return s_; }

  /// The port's descriptor while the link is up, else -1. The board has no
  /// watchdog and the port is exclusive (no second open), so a crash handler
  /// that must zero the torque keeps a dup() of this descriptor
  /// (haptic-server's crash outputs). Any thread.
  int port_descriptor() const noexcept { return port_fd_.load(); }
  /// The state command with zero torque on every motor, as the crash handler
  /// writes it; returns its length (<= haply::kMaxFrame).
  std::size_t zero_torque_frame(std::uint8_t* out) const noexcept;

 private:
  /// Reset, setup, and state requests until the first valid reply; throws.
  void handshake(SerialPort& port);
  void io_loop();
  /// One request and its reply. False when the link was lost.
  bool exchange(realtime::LatestValueReader<Command>& commands);
  void link_lost(const std::string& why);
  /// Empty when the handle at motor angles `q` is within the workspace and
  /// its margin, else why not.
  std::string check_workspace(const JointArray& q) const;

  HaplySettings s_;
  SerialPort port_;  // the I/O thread's while link_up_; the setup path's otherwise
  std::atomic<bool> running_{false};
  std::atomic<int> port_fd_{-1};  // port_'s descriptor while the link is up
  // I/O thread only:
  DeviceReading sample_;
  std::int64_t last_reply_ns_ = 0;
  int bad_replies_ = 0;
  std::thread io_;
};

/// CDC-ACM serial ports in `sysfs_root` (/sys): candidates for the `haply`
/// driver. The board announces nothing a host could check before a
/// handshake, so every such port is listed, with its USB IDs and names.
std::vector<ConnectedDevice> list_serial_boards(const std::filesystem::path& sysfs_root = "/sys");

/// Registers `haply` (called by register_builtin_drivers).
void register_haply_driver(DriverRegistry& registry,
                           std::shared_ptr<const Clock> clock = monotonic_clock());

}  // namespace tsmh::master_devices
