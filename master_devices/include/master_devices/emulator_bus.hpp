#pragma once
// An in-process "USB bus" with one emulated console plugged in: the
// Firmware behind the Transport interface, so the console driver's real code
// (decoding, calibration, limits, watchdog feeding, disconnect and reconnect)
// runs in tests exactly as against hidapi or libusb.
//
// Two pacings: kRealTime runs the firmware on its own thread at its nominal
// rate (absolute deadlines on CLOCK_MONOTONIC), like hardware; kManual
// advances one firmware period per tick() call on the caller's thread, for
// deterministic tests. Either way, input reports are stamped on arrival with
// Options::clock, the host clock the driver reads too: a manual-paced test
// gives both the same ManualClock and advances it with its ticks.
// unplug()/replug() simulate the cable: the open transport reports the link
// lost on its next tick (as hid_read() returns -1), enumerate() stops
// listing the device until replugged.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "master_devices/clock.hpp"
#include "master_devices/firmware.hpp"
#include "master_devices/transport.hpp"

namespace tsmh::master_devices {

class EmulatorBus final : public TransportProvider {
 public:
  enum class Pacing { kManual, kRealTime };

  struct Options {
    Pacing pacing = Pacing::kRealTime;
    /// Stamps each input report's arrival (TransportListener::on_input_report).
    std::shared_ptr<const Clock> clock = monotonic_clock();
    FirmwareConfig firmware = default_console_firmware();
    std::uint16_t vendor_id = 0x1209;
    std::uint16_t product_id = 0x0001;
    std::string serial = "EMU-0001";
    std::string path = "emu:0";
    /// Called at each tick (the firmware locked) before each firmware
    /// step, e.g. to apply an operator's hand torque. Optional.
    std::function<void(Firmware&, std::int64_t dt_ns)> world;
    /// Called (firmware locked) right after the firmware accepted an output
    /// report: lets benchmarks time command-to-motor latency. Optional.
    std::function<void(const Firmware&)> after_output;
    /// Start unplugged (replug() plugs it in).
    bool start_unplugged = false;
  };

  explicit EmulatorBus(Options options);
  ~EmulatorBus() override;
  EmulatorBus(const EmulatorBus&) = delete;
  EmulatorBus& operator=(const EmulatorBus&) = delete;

  // ---- TransportProvider ----
  std::string_view name() const override { return "emulator"; }
  std::vector<TransportDeviceInfo> enumerate(std::uint16_t vendor_id,
                                             std::uint16_t product_id) override;
  std::unique_ptr<Transport> open(const TransportDeviceInfo& device) override;
  void set_arrival_callback(std::function<void()> callback) override;

  // ---- the world ----
  void unplug();
  void replug();
  bool plugged() const;
  /// kManual only: one firmware period, then one input report to the open transport.
  void tick();
  /// Flips one bit in each of the next `n` input reports (a noisy link or a
  /// firmware bug): the host must drop them, and fault after too many.
  void corrupt_next_input_reports(int n);
  /// Runs `f` with the firmware locked (buttons, hand torque, observation).
  void with_firmware(const std::function<void(Firmware&)>& f);
  std::int64_t period_ns() const { return period_ns_; }

  struct Session;  // one open transport's link state (internal)

 private:
  friend class EmulatorTransport;
  void run_real_time();
  void tick_once();

  Options options_;
  std::int64_t period_ns_;
  mutable std::mutex mutex_;   // firmware, plugged_, session_
  std::mutex delivery_mutex_;  // held while a listener callback runs
  Firmware firmware_;
  bool plugged_ = true;
  int corrupt_ = 0;
  std::shared_ptr<Session> session_;  // the open transport, if any
  std::function<void()> arrival_;
  std::atomic<bool> stopping_{false};
  std::thread pacing_thread_;
};

}  // namespace tsmh::master_devices
