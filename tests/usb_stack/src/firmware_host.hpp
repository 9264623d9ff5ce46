#pragma once
// Runs the console firmware (master_devices' Firmware, pure and
// single-threaded) in real time inside a gadget program: a clock thread steps
// it every millisecond on absolute deadlines and publishes each new input
// report; the gadget's endpoint threads feed output and feature reports in.
// One mutex serialises the Firmware: this is test scaffolding on the device
// side of the cable, not the host's real-time path.
//
// It also watches what the test must judge on the device side: gaps in the
// host's output sequence, and every watchdog trip (how long after the last
// output report it fired, and whether the motor current went to zero).

#include <array>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <optional>
#include <span>
#include <thread>

#include "master_devices/firmware.hpp"
#include "master_devices/protocol.hpp"

namespace tsmh::usb_stack {

struct WatchdogTrip {
  double since_output_ms = 0.0;    ///< wall time from the last accepted output report to the trip
  double current_before_ma = 0.0;  ///< largest |motor current| in the step before the trip
  double current_after_ma = 0.0;   ///< largest |motor current| right after the trip
  std::uint16_t watchdog_ms = 0;   ///< the watchdog time programmed by the host
};

struct FirmwareHostStats {
  master_devices::FirmwareStats firmware;
  /// Output reports skipped (sequence advanced by more than one): allowed,
  /// a driver may drop a superseded command, but reported.
  std::uint64_t output_sequence_gaps = 0;
  /// Output reports repeated or out of order: never allowed.
  std::uint64_t output_sequence_reorders = 0;
  std::uint64_t link_losses = 0;
  std::uint64_t late_ticks = 0;  ///< clock ticks more than one period late
};

class FirmwareHost {
 public:
  explicit FirmwareHost(const master_devices::FirmwareConfig& config);
  ~FirmwareHost();
  FirmwareHost(const FirmwareHost&) = delete;
  FirmwareHost& operator=(const FirmwareHost&) = delete;

  /// Starts the 1 kHz clock thread.
  void start();

  /// Copies the newest input report into `out` once there is one newer than
  /// `counter` (updated), waiting at most timeout_ms. Returns its size, or 0
  /// on timeout.
  std::size_t wait_input_report(std::span<std::uint8_t> out, std::uint64_t& counter,
                                int timeout_ms);
  /// A fresh input report made now (GET_REPORT(Input) on ep0).
  std::size_t make_input_report(std::span<std::uint8_t> out);

  master_devices::protocol::Error on_output_report(std::span<const std::uint8_t> bytes);
  std::size_t get_feature(std::uint8_t report_id, std::span<std::uint8_t> out);
  master_devices::protocol::Error set_feature(std::span<const std::uint8_t> bytes);

  /// The gadget was disabled (unbound, reset): the firmware drops its motors.
  void on_link_lost();

  /// The watchdog trip in force now (no output report accepted since), if any.
  std::optional<WatchdogTrip> current_watchdog_trip();
  FirmwareHostStats stats();

 private:
  void run_clock();
  /// Steps the firmware up to now (mutex held): events are then handled at
  /// their real time, not at the previous tick's.
  void advance_locked(std::int64_t now);

  master_devices::Firmware firmware_;
  std::mutex mutex_;
  std::condition_variable new_report_;
  std::array<std::uint8_t, master_devices::protocol::kMaxReportSize> report_{};
  std::size_t report_size_ = 0;
  std::uint64_t report_counter_ = 0;
  std::int64_t last_output_ns_ = 0;
  std::int64_t stepped_to_ns_ = 0;  // wall time the firmware clock has reached
  bool have_output_sequence_ = false;
  std::uint16_t last_output_sequence_ = 0;
  std::optional<WatchdogTrip> trip_;
  FirmwareHostStats stats_;
  std::atomic<bool> running_{false};
  std::thread clock_;
};

/// Largest |motor current| of the firmware's joints, mA.
double max_abs_current_ma(const master_devices::Firmware& f);

}  // namespace tsmh::usb_stack
