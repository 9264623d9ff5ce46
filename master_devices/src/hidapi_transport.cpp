#include "master_devices/hidapi_transport.hpp"

#include <hidapi/hidapi.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <thread>

#include "master_devices/clock.hpp"
#include "master_devices/protocol.hpp"

namespace tsmh::master_devices {

std::string utf8_from_wide(const wchar_t* s) {
  std::string out;
  if (s == nullptr) return out;
  for (; *s != L'\0'; ++s) {
    const auto c = static_cast<std::uint32_t>(*s);
    if (c < 0x80) {
      out += static_cast<char>(c);
    } else if (c < 0x800) {
      out += static_cast<char>(0xC0 | (c >> 6));
      out += static_cast<char>(0x80 | (c & 0x3F));
    } else if (c < 0x10000) {
      out += static_cast<char>(0xE0 | (c >> 12));
      out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (c & 0x3F));
    } else if (c < 0x110000) {
      out += static_cast<char>(0xF0 | (c >> 18));
      out += static_cast<char>(0x80 | ((c >> 12) & 0x3F));
      out += static_cast<char>(0x80 | ((c >> 6) & 0x3F));
      out += static_cast<char>(0x80 | (c & 0x3F));
    }
  }
  return out;
}

namespace {

std::string hid_error_text(hid_device* dev) {
  const std::string text = utf8_from_wide(hid_error(dev));
  return text.empty() ? "unknown hidapi error" : text;
}

class HidapiTransport final : public Transport {
 public:
  HidapiTransport(hid_device* dev, TransportDeviceInfo info, int read_timeout_ms,
                  std::shared_ptr<const Clock> clock)
      : dev_(dev),
        info_(std::move(info)),
        read_timeout_ms_(read_timeout_ms),
        clock_(std::move(clock)) {}
  ~HidapiTransport() override {
    stop();
    hid_close(dev_);
  }

  const TransportDeviceInfo& info() const override { return info_; }

  std::size_t get_feature(std::uint8_t report_id, std::span<std::uint8_t> out) override {
    if (out.empty()) throw TransportError(info_.path + ": empty feature buffer");
    out[0] = report_id;  // hidapi: the report ID goes in the first byte
    const int n = hid_get_feature_report(dev_, out.data(), out.size());
    if (n < 0) {
      throw TransportError(info_.path + ": GET_REPORT(Feature " + std::to_string(report_id) +
                           "): " + hid_error_text(dev_));
    }
    return static_cast<std::size_t>(n);
  }

  void set_feature(std::span<const std::uint8_t> report) override {
    const int n = hid_send_feature_report(dev_, report.data(), report.size());
    if (n < 0) throw TransportError(info_.path + ": SET_REPORT(Feature): " + hid_error_text(dev_));
  }

  void start(TransportListener& listener) override {
    stop();
    stopping_ = false;
    reader_ = std::thread([this, &listener] { read_loop(listener); });
  }

  void stop() noexcept override {
    stopping_ = true;
    if (reader_.joinable()) reader_.join();
  }

  bool write_output(std::span<const std::uint8_t> report) noexcept override {
    // Runs on the reader thread (inside on_input_report). While newer input
    // reports are already queued, the answer is kept and superseded by the
    // next one's: newest wins, as over libusb.
    if (report.size() > pending_.size()) return false;
    if (more_queued_) {
      std::copy(report.begin(), report.end(), pending_.begin());
      pending_size_ = report.size();
      return true;
    }
    pending_size_ = 0;
    return send(report);
  }

 private:
  // hidraw queues up to 64 reports while this thread is not running.
  static constexpr std::size_t kMaxBatch = 64;

  bool send(std::span<const std::uint8_t> report) noexcept {
    // hidraw sends it on the interrupt OUT endpoint (or SET_REPORT(Output)
    // when the device has none) and waits for it: up to a frame at full speed.
    return hid_write(dev_, report.data(), report.size()) == static_cast<int>(report.size());
  }

  void lost(TransportListener& listener) {
    // The hidraw node is gone (unplug) or broken: one notification, then stop.
    std::array<char, 160> why{};
    const std::string text = hid_error_text(dev_);
    text.copy(why.data(), why.size() - 1);
    listener.on_link_lost(why.data());
  }

  void read_loop(TransportListener& listener) {
    std::array<std::array<std::uint8_t, 64>, kMaxBatch> bufs{};
    std::array<std::size_t, kMaxBatch> sizes{};
    while (!stopping_) {
      const int n = hid_read_timeout(dev_, bufs[0].data(), bufs[0].size(), read_timeout_ms_);
      if (n < 0) return lost(listener);
      if (n == 0) continue;  // timeout: staleness is judged by the driver's read()
      const std::int64_t arrival = clock_->now_ns();
      // Take everything already queued (a starved thread finds a backlog):
      // each report still reaches the driver, which dates it on the device
      // clock, but only the newest is answered. Answering each with a write
      // that waits for the bus would never drain a backlog at full speed.
      sizes[0] = static_cast<std::size_t>(n);
      std::size_t count = 1;
      bool gone = false;
      while (count < kMaxBatch) {
        const int m = hid_read_timeout(dev_, bufs[count].data(), bufs[count].size(), 0);
        if (m < 0) gone = true;
        if (m <= 0) break;
        sizes[count++] = static_cast<std::size_t>(m);
      }
      for (std::size_t i = 0; i < count; ++i) {
        more_queued_ = i + 1 < count;
        listener.on_input_report(std::span<const std::uint8_t>(bufs[i].data(), sizes[i]), arrival);
      }
      more_queued_ = false;
      if (pending_size_ > 0) {  // the newest report was not answered: send the last answer
        send(std::span<const std::uint8_t>(pending_.data(), pending_size_));
        pending_size_ = 0;
      }
      if (gone) return lost(listener);
    }
  }

  hid_device* dev_;
  TransportDeviceInfo info_;
  int read_timeout_ms_;
  std::shared_ptr<const Clock> clock_;
  std::atomic<bool> stopping_{false};
  std::thread reader_;
  // Reader thread only.
  bool more_queued_ = false;
  std::array<std::uint8_t, protocol::kMaxReportSize> pending_{};
  std::size_t pending_size_ = 0;
};

}  // namespace

HidapiProvider::HidapiProvider() : HidapiProvider(Options{}) {}

HidapiProvider::HidapiProvider(Options options) : options_(std::move(options)) {
  if (!options_.clock) options_.clock = monotonic_clock();
  // hidapi keeps process-wide state; hid_init() is idempotent and we never
  // call hid_exit() (another provider may still be using it).
  hid_init();
}

std::vector<TransportDeviceInfo> HidapiProvider::enumerate(std::uint16_t vendor_id,
                                                           std::uint16_t product_id) {
  std::vector<TransportDeviceInfo> out;
  hid_device_info* list = hid_enumerate(vendor_id, product_id);
  for (hid_device_info* d = list; d != nullptr; d = d->next) {
    if (options_.usage_page != 0 && d->usage_page != 0 && d->usage_page != options_.usage_page) {
      continue;
    }
    out.push_back(TransportDeviceInfo{
        d->path ? d->path : "", d->vendor_id, d->product_id, utf8_from_wide(d->serial_number),
        utf8_from_wide(d->manufacturer_string), utf8_from_wide(d->product_string)});
  }
  hid_free_enumeration(list);
  return out;
}

std::unique_ptr<Transport> HidapiProvider::open(const TransportDeviceInfo& device) {
  hid_device* dev = hid_open_path(device.path.c_str());
  if (dev == nullptr) {
    const std::string why = utf8_from_wide(hid_error(nullptr));
    throw TransportError(device.path + ": hid_open_path failed" + (why.empty() ? "" : ": " + why) +
                         " (no permission? install the udev rules, see docs/master-devices.md)");
  }
  return std::make_unique<HidapiTransport>(dev, device, options_.read_timeout_ms, options_.clock);
}

}  // namespace tsmh::master_devices
