#pragma once
// The host driver for our console protocol (docs/hid-protocol.md) over any
// Transport: registered as `hid` (hidapi), `usb` (libusb) and `emulator`
// (in-process firmware). Everything protocol- and safety-related lives here,
// so all three run the same code:
//
// - open(): find the device (path / serial / first with the profile's
//   VID/PID), read DEVICE_INFO and check it against the profile, program
//   CALIBRATION (watchdog, current limits) and read it back.
// - I/O context (per input report): decode, date the sample on the device's
//   own clock (DeviceClock), calibrate to rad, estimate velocity on the
//   device clock, check workspace and device faults, publish the reading;
//   then answer with one output report carrying the newest torque command
//   (clamped, I^2 t limited, zero when disabled, faulted, when the loop
//   stopped writing for command_timeout_ms, or when the report itself
//   arrived later than the freshness bound).
// - read() (the loop): kDisconnected, torque zero, as soon as the newest
//   sample is older than the freshness bound (a few device periods), and OK
//   again as soon as fresh samples arrive: silence is noticed within a loop
//   cycle of the bound, whatever the kernel's or library's unplug path takes.
// - Supervisor thread: on link loss, tears the transport down and reconnects
//   every reconnect_interval_ms (or at once on a hotplug arrival). The device
//   comes back disabled.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "config/field_reader.hpp"
#include "master_devices/clock.hpp"
#include "master_devices/device_clock.hpp"
#include "master_devices/driver_base.hpp"
#include "master_devices/joint_calibration.hpp"
#include "master_devices/profile.hpp"
#include "master_devices/protocol.hpp"
#include "master_devices/transport.hpp"
#include "realtime/latest_value.hpp"

namespace tsmh::master_devices {

struct ConsoleSettings {
  std::string path;    ///< open this device path; "" = any with the profile's VID/PID
  std::string serial;  ///< only a device with this serial; "" = any
  std::int64_t reconnect_interval_ms = 200;
  std::int64_t command_timeout_ms = 20;  ///< zero torque when write_torque() calls stop this long
  /// The freshness bound: read() says kDisconnected (stale) when the newest
  /// sample is older, and a report arriving later than this carries no
  /// torque. 0: stale_periods device periods (1 / DEVICE_INFO nominal rate).
  std::int64_t stale_timeout_ms = 0;
  double stale_periods = 3.0;
  /// DeviceClock: largest device-vs-host clock rate difference followed.
  double clock_tolerance_ppm = DeviceClock::kDefaultTolerancePpm;
  double velocity_cutoff_hz = 150.0;
  double workspace_margin_rad = 0.2;  ///< kFault when a joint is this far outside its workspace
  int max_bad_reports = 10;           ///< consecutive malformed reports before kFault
  bool wait_for_device = false;       ///< open() succeeds with no device and waits for it
};

/// Reads ConsoleSettings keys from a driver settings map (all optional).
/// `profile` is returned separately by the caller; this ignores it.
ConsoleSettings parse_console_settings(config::FieldReader& r);

struct ConsoleStats {
  std::uint64_t reports = 0;       ///< valid input reports
  std::uint64_t bad_reports = 0;   ///< malformed input reports (dropped)
  std::uint64_t lost_reports = 0;  ///< gaps in the input sequence
  std::uint64_t late_reports =
      0;  ///< arrived later than the freshness bound (answered without torque)
  std::uint64_t outputs_sent = 0;
  std::uint64_t outputs_failed = 0;
  std::uint64_t disconnects = 0;
  std::uint64_t reconnects = 0;
};

class ConsoleDevice final : public DriverBase, private TransportListener {
 public:
  /// `clock` stamps torque commands (their age is checked against each
  /// report's arrival): give it the clock the transport stamps arrivals with.
  ConsoleDevice(std::string driver, DeviceProfile profile, ConsoleSettings settings,
                std::shared_ptr<TransportProvider> provider,
                std::shared_ptr<const Clock> clock = monotonic_clock());
  ~ConsoleDevice() override;

  void open() override;
  void close() noexcept override;
  bool clear_fault() override;

  ConsoleStats stats() const;
  const DeviceProfile& profile() const { return profile_; }
  /// Path of the connected device ("" when disconnected).
  std::string connected_path() const;
  /// read() says kDisconnected (stale) when the newest sample is older than
  /// this: stale_timeout_ms, or stale_periods / nominal rate once connected.
  std::int64_t freshness_bound_ns() const noexcept override { return fresh_bound_ns_.load(); }

 private:
  // TransportListener (I/O context)
  void on_input_report(std::span<const std::uint8_t> report, std::int64_t t_ns) noexcept override;
  void on_link_lost(const char* why) noexcept override;

  void connect();  // setup: find, handshake, start. Throws DeviceError.
  void supervise();
  void send_output(std::int64_t t_ns, double dt_s, bool allow_torque) noexcept;
  void latch_fault(FaultCode code, const char* text) noexcept;
  void set_error_fixed(const char* text) noexcept;

  std::string driver_;
  DeviceProfile profile_;
  ConsoleSettings settings_;
  std::shared_ptr<TransportProvider> provider_;

  realtime::LatestValueReader<Command> command_reader_{commands_};  // the I/O thread's
  std::atomic<bool> clear_device_fault_{false};
  std::atomic<std::int64_t> fresh_bound_ns_{0};

  // I/O context state (one session at a time; reset in connect()).
  Transport* active_ = nullptr;
  bool have_previous_ = false;
  std::uint16_t previous_sequence_ = 0;
  std::uint32_t previous_device_us_ = 0;
  DeviceClock device_clock_;
  int bad_in_a_row_ = 0;
  std::uint64_t reading_count_ = 0;
  std::array<VelocityEstimator, kMaxDof> velocity_{};
  std::array<CurrentLimiter, kMaxDof> limiters_{};
  std::uint16_t output_sequence_ = 0;
  JointArray last_sent_{};

  // Counters (I/O context writes, anyone reads).
  std::atomic<std::uint64_t> n_reports_{0}, n_bad_{0}, n_lost_{0}, n_late_{0}, n_sent_{0},
      n_failed_{0}, n_disconnects_{0}, n_reconnects_{0};

  // Supervisor.
  mutable std::mutex mutex_;  // guards the fields below
  std::condition_variable wake_;
  bool link_lost_ = false;
  std::string loss_reason_;  // why the link went down, kept for reconnect errors
  bool arrival_ = false;
  bool stopping_ = false;
  std::unique_ptr<Transport> transport_;
  std::string connected_path_;
  std::thread supervisor_;
  // error_ (DriverBase) has reserved capacity, so that the I/O context
  // records an error without allocating.
};

}  // namespace tsmh::master_devices
