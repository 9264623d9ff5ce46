#pragma once
// The transport beneath the console drivers: moves protocol reports (bytes,
// report-ID first) between the host driver and a device. Implementations:
// hidapi (hidraw), libusb (vendor interface, async transfers), and the
// in-process emulator, so the driver's own code runs unchanged against any.
//
// Input is pushed: the transport's I/O context (a reader thread, libusb's
// event thread, the emulator's clock) calls the listener for every input
// report; the listener answers with write_output() from inside that call.
// One output report per input report keeps the host in lock-step with the
// device clock and needs no extra thread.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace tsmh::master_devices {

/// A transport operation failed; the message names the device path and cause.
class TransportError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One device a provider can see.
struct TransportDeviceInfo {
  std::string path;  ///< how to open it: "/dev/hidraw3", "usb:1-4.2", "emu:0"
  std::uint16_t vendor_id = 0;
  std::uint16_t product_id = 0;
  std::string serial;  ///< may be empty (no permission to read it)
  std::string manufacturer;
  std::string product;
};

/// Receives what a transport reads. Called from the transport's I/O context;
/// implementations must be quick and must not call Transport::stop().
class TransportListener {
 public:
  /// One complete input report (report-ID byte first), arrival time on CLOCK_MONOTONIC.
  virtual void on_input_report(std::span<const std::uint8_t> report,
                               std::int64_t t_ns) noexcept = 0;
  /// The link is gone (unplugged, I/O error). The last callback of this start().
  virtual void on_link_lost(const char* why) noexcept = 0;

 protected:
  ~TransportListener() = default;
};

class Transport {
 public:
  virtual ~Transport() = default;
  virtual const TransportDeviceInfo& info() const = 0;

  /// GET_REPORT(Feature). Setup only (before start()). `out[0]` need not be
  /// set. Returns the report size, report ID first. Throws TransportError.
  virtual std::size_t get_feature(std::uint8_t report_id, std::span<std::uint8_t> out) = 0;
  /// SET_REPORT(Feature), report ID first. Setup only. Throws TransportError.
  virtual void set_feature(std::span<const std::uint8_t> report) = 0;

  /// Starts delivering input reports to `listener` until stop() or on_link_lost().
  virtual void start(TransportListener& listener) = 0;
  /// No callback runs once this returns. Not to be called from a callback. Idempotent.
  virtual void stop() noexcept = 0;

  /// Sends one output report (report ID first). Called from inside
  /// on_input_report. Bounded time; false when the report could not be sent.
  virtual bool write_output(std::span<const std::uint8_t> report) noexcept = 0;
};

/// Finds and opens devices of one kind of transport.
class TransportProvider {
 public:
  virtual ~TransportProvider() = default;
  /// "hidapi", "libusb" or "emulator".
  virtual std::string_view name() const = 0;
  /// Devices with this VID/PID that are present now. Never throws for "none found".
  virtual std::vector<TransportDeviceInfo> enumerate(std::uint16_t vendor_id,
                                                     std::uint16_t product_id) = 0;
  /// Opens one of the enumerated devices. Throws TransportError.
  virtual std::unique_ptr<Transport> open(const TransportDeviceInfo& device) = 0;
  /// Optional hotplug: `callback` (any thread, quick) is called when a device
  /// may have arrived, so drivers reconnect without waiting for their poll.
  virtual void set_arrival_callback(std::function<void()> callback) { (void)callback; }
};

}  // namespace tsmh::master_devices
