#pragma once
// hidapi (hidraw backend) transport for the console: a reader thread blocks in
// hid_read_timeout() and hands each input report to the listener; output
// reports go out with hid_write() from that thread, features with
// hid_{get,send}_feature_report(). All our reports are numbered, so the
// report-ID byte is always the first byte in both directions, as hidapi
// expects. hid_read_timeout() returning -1 (the hidraw node went away) is
// reported as a lost link at once. After each wake-up the reader takes every
// report hidraw has queued meanwhile and answers only the newest, so a
// backlog left by a stall drains at once instead of persisting.

#include <memory>

#include "master_devices/clock.hpp"
#include "master_devices/transport.hpp"

namespace tsmh::master_devices {

class HidapiProvider final : public TransportProvider {
 public:
  struct Options {
    int read_timeout_ms = 10;  ///< bounds how long stop() waits for the reader thread
    /// Only list HID interfaces with this usage page (the console's vendor
    /// page), so a composite device's keyboard interface is never opened.
    /// 0 = any.
    unsigned short usage_page = 0xFF00;
    /// Stamps each input report's arrival (the driver's clock).
    std::shared_ptr<const Clock> clock = monotonic_clock();
  };
  HidapiProvider();
  explicit HidapiProvider(Options options);

  std::string_view name() const override { return "hidapi"; }
  std::vector<TransportDeviceInfo> enumerate(std::uint16_t vendor_id,
                                             std::uint16_t product_id) override;
  std::unique_ptr<Transport> open(const TransportDeviceInfo& device) override;

 private:
  Options options_;
};

/// UTF-8 from hidapi's wide strings (UTF-32 on Linux); "" for null.
std::string utf8_from_wide(const wchar_t* s);

}  // namespace tsmh::master_devices
