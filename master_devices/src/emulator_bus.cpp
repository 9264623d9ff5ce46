#include "master_devices/emulator_bus.hpp"

#include <time.h>

#include <array>

#include "master_devices/clock.hpp"
#include "realtime/clock.hpp"
#include "realtime/pacing.hpp"

namespace tsmh::master_devices {

struct EmulatorBus::Session {
  TransportListener* listener = nullptr;  // set by start(), cleared by stop()
  bool lost = false;                      // unplugged: report on the next tick
  bool closed = false;                    // the transport was destroyed
};

/// The transport handed out by EmulatorBus::open().
class EmulatorTransport final : public Transport {
 public:
  EmulatorTransport(EmulatorBus& bus, std::shared_ptr<EmulatorBus::Session> session,
                    TransportDeviceInfo info)
      : bus_(bus), session_(std::move(session)), info_(std::move(info)) {}

  ~EmulatorTransport() override {
    stop();
    std::lock_guard lock(bus_.mutex_);
    session_->closed = true;
    if (bus_.session_ == session_) bus_.session_.reset();
  }

  const TransportDeviceInfo& info() const override { return info_; }

  std::size_t get_feature(std::uint8_t report_id, std::span<std::uint8_t> out) override {
    std::lock_guard lock(bus_.mutex_);
    check_link();
    const std::size_t n = bus_.firmware_.get_feature(report_id, out);
    if (n == 0) {
      throw TransportError(info_.path + ": GET_REPORT(Feature " + std::to_string(report_id) +
                           ") stalled: no such report");
    }
    return n;
  }

  void set_feature(std::span<const std::uint8_t> report) override {
    std::lock_guard lock(bus_.mutex_);
    check_link();
    if (const protocol::Error e = bus_.firmware_.set_feature(report)) {
      throw TransportError(info_.path + ": SET_REPORT(Feature) stalled: " + protocol::describe(e));
    }
  }

  void start(TransportListener& listener) override {
    std::lock_guard lock(bus_.mutex_);
    check_link();
    session_->listener = &listener;
  }

  void stop() noexcept override {
    // Waiting for delivery_mutex_ guarantees no callback is still running.
    std::lock_guard delivery(bus_.delivery_mutex_);
    std::lock_guard lock(bus_.mutex_);
    session_->listener = nullptr;
  }

  bool write_output(std::span<const std::uint8_t> report) noexcept override {
    std::lock_guard lock(bus_.mutex_);
    if (session_->lost || !bus_.plugged_) return false;
    // The firmware ignores (and counts) malformed reports, like a real device.
    if (!bus_.firmware_.on_output_report(report) && bus_.options_.after_output) {
      bus_.options_.after_output(bus_.firmware_);
    }
    return true;
  }

 private:
  void check_link() const {
    if (session_->lost || !bus_.plugged_) throw TransportError(info_.path + ": device unplugged");
  }

  EmulatorBus& bus_;
  std::shared_ptr<EmulatorBus::Session> session_;
  TransportDeviceInfo info_;
};

EmulatorBus::EmulatorBus(Options options)
    : options_(std::move(options)),
      period_ns_(1'000'000'000LL / std::max<int>(1, options_.firmware.info.nominal_rate_hz)),
      firmware_(options_.firmware),
      plugged_(!options_.start_unplugged) {
  if (!options_.clock) options_.clock = monotonic_clock();
  if (options_.pacing == Pacing::kRealTime)
    pacing_thread_ = std::thread([this] { run_real_time(); });
}

EmulatorBus::~EmulatorBus() {
  stopping_ = true;
  if (pacing_thread_.joinable()) pacing_thread_.join();
}

std::vector<TransportDeviceInfo> EmulatorBus::enumerate(std::uint16_t vendor_id,
                                                        std::uint16_t product_id) {
  std::lock_guard lock(mutex_);
  if (!plugged_ || vendor_id != options_.vendor_id || product_id != options_.product_id) return {};
  return {TransportDeviceInfo{options_.path, options_.vendor_id, options_.product_id,
                              options_.serial, "tsm-haptics", "emulated 2-DOF console"}};
}

std::unique_ptr<Transport> EmulatorBus::open(const TransportDeviceInfo& device) {
  std::lock_guard lock(mutex_);
  if (device.path != options_.path) throw TransportError(device.path + ": no such device");
  if (!plugged_) throw TransportError(device.path + ": device unplugged");
  if (session_ && !session_->closed && !session_->lost) {
    throw TransportError(device.path + ": already open (one host at a time)");
  }
  session_ = std::make_shared<Session>();
  return std::make_unique<EmulatorTransport>(
      *this, session_,
      TransportDeviceInfo{options_.path, options_.vendor_id, options_.product_id, options_.serial,
                          "tsm-haptics", "emulated 2-DOF console"});
}

void EmulatorBus::set_arrival_callback(std::function<void()> callback) {
  std::lock_guard lock(mutex_);
  arrival_ = std::move(callback);
}

void EmulatorBus::unplug() {
  std::lock_guard lock(mutex_);
  if (!plugged_) return;
  plugged_ = false;
  firmware_.on_link_lost();
  if (session_) session_->lost = true;
}

void EmulatorBus::replug() {
  std::function<void()> arrival;
  {
    std::lock_guard lock(mutex_);
    if (plugged_) return;
    plugged_ = true;
    arrival = arrival_;
  }
  if (arrival) arrival();
}

bool EmulatorBus::plugged() const {
  std::lock_guard lock(mutex_);
  return plugged_;
}

void EmulatorBus::with_firmware(const std::function<void(Firmware&)>& f) {
  std::lock_guard lock(mutex_);
  f(firmware_);
}

void EmulatorBus::tick() {
  tick_once();
}

void EmulatorBus::corrupt_next_input_reports(int n) {
  std::lock_guard lock(mutex_);
  corrupt_ = n;
}

void EmulatorBus::tick_once() {
  std::array<std::uint8_t, protocol::kMaxReportSize> report{};
  std::size_t size = 0;
  bool deliver_lost = false;
  std::shared_ptr<Session> session;
  {
    std::lock_guard lock(mutex_);
    if (options_.world) options_.world(firmware_, period_ns_);
    firmware_.step(period_ns_);
    // The device is powered from its own supply: the mechanism keeps moving
    // while unplugged, but nothing reaches the host.
    session = session_;
    if (!session || session->listener == nullptr) return;
    if (session->lost) {
      deliver_lost = true;
    } else {
      size = firmware_.make_input_report(report);
      if (corrupt_ > 0) {
        --corrupt_;
        report[8] ^= 0x10;  // inside counts[0]: only the CRC can tell
      }
    }
  }
  std::lock_guard delivery(delivery_mutex_);
  TransportListener* listener = nullptr;
  {
    std::lock_guard lock(mutex_);
    listener = session->listener;  // stop() may have run in between
    if (deliver_lost) session->listener = nullptr;
  }
  if (listener == nullptr) return;
  if (deliver_lost) {
    listener->on_link_lost("device unplugged (emulator)");
  } else {
    listener->on_input_report(std::span<const std::uint8_t>(report.data(), size),
                              options_.clock->now_ns());
  }
}

void EmulatorBus::run_real_time() {
  // Real-time pacing is real by definition: CLOCK_MONOTONIC, whatever
  // Options::clock stamps the reports with. Every period runs, late ones
  // back to back: a real console keeps its own clock and the kernel queues
  // what the host did not read in time.
  realtime::Pacer pace(period_ns_, realtime::monotonic_now_ns() + period_ns_);
  while (!stopping_) {
    pace.wait_through_signals();
    tick_once();
    pace.advance_every();
  }
}

}  // namespace tsmh::master_devices
