#include "firmware_host.hpp"

#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "realtime/clock.hpp"

namespace tsmh::usb_stack {

namespace md = tsmh::master_devices;
namespace protocol = tsmh::master_devices::protocol;

namespace {
constexpr std::int64_t kPeriodNs = 1'000'000;  // the console's nominal 1 kHz
}  // namespace

double max_abs_current_ma(const md::Firmware& f) {
  double m = 0.0;
  for (std::size_t j = 0; j < protocol::kJoints; ++j)
    m = std::max(m, std::abs(f.applied_current_a(j)) * 1e3);
  return m;
}

FirmwareHost::FirmwareHost(const md::FirmwareConfig& config)
    : firmware_(config), stepped_to_ns_(realtime::monotonic_now_ns()) {}

FirmwareHost::~FirmwareHost() {
  running_ = false;
  if (clock_.joinable()) clock_.join();
}

void FirmwareHost::start() {
  running_ = true;
  clock_ = std::thread([this] { run_clock(); });
}

void FirmwareHost::advance_locked(std::int64_t now) {
  const bool was_tripped = firmware_.watchdog_tripped();
  const double before = max_abs_current_ma(firmware_);
  // Real elapsed time, so the firmware clock (and its watchdog) keeps wall
  // time even when the clock thread runs late.
  if (now > stepped_to_ns_) firmware_.step(now - stepped_to_ns_);
  stepped_to_ns_ = std::max(stepped_to_ns_, now);
  if (!was_tripped && firmware_.watchdog_tripped()) {
    WatchdogTrip t;
    t.since_output_ms = static_cast<double>(now - last_output_ns_) * 1e-6;
    t.current_before_ma = before;
    t.current_after_ma = max_abs_current_ma(firmware_);
    t.watchdog_ms = firmware_.calibration().watchdog_ms;
    trip_ = t;
  }
}

void FirmwareHost::run_clock() {
  std::int64_t deadline = realtime::monotonic_now_ns();
  while (running_) {
    deadline += kPeriodNs;
    realtime::sleep_until_ns(deadline);
    const std::int64_t now = realtime::monotonic_now_ns();
    {
      std::lock_guard lock(mutex_);
      if (now - deadline > kPeriodNs) ++stats_.late_ticks;
      advance_locked(now);
      report_size_ = firmware_.make_input_report(report_);
      ++report_counter_;
    }
    new_report_.notify_all();
    // Re-base after a long stall instead of bursting to catch up.
    if (realtime::monotonic_now_ns() - deadline > 10 * kPeriodNs)
      deadline = realtime::monotonic_now_ns();
  }
}

std::size_t FirmwareHost::wait_input_report(std::span<std::uint8_t> out, std::uint64_t& counter,
                                            int timeout_ms) {
  std::unique_lock lock(mutex_);
  if (!new_report_.wait_for(lock, std::chrono::milliseconds(timeout_ms),
                            [&] { return report_counter_ > counter; }))
    return 0;
  counter = report_counter_;
  const std::size_t n = std::min(report_size_, out.size());
  std::copy_n(report_.begin(), n, out.begin());
  return n;
}

std::size_t FirmwareHost::make_input_report(std::span<std::uint8_t> out) {
  std::lock_guard lock(mutex_);
  advance_locked(realtime::monotonic_now_ns());
  return firmware_.make_input_report(out);
}

protocol::Error FirmwareHost::on_output_report(std::span<const std::uint8_t> bytes) {
  std::lock_guard lock(mutex_);
  advance_locked(realtime::monotonic_now_ns());
  const protocol::Error e = firmware_.on_output_report(bytes);
  if (!e) {
    last_output_ns_ = stepped_to_ns_;
    trip_.reset();  // the host is back: that trip is over
    const auto seq = protocol::decode_output(bytes).value.sequence;
    const std::uint16_t step = protocol::sequence_delta(last_output_sequence_, seq);
    if (have_output_sequence_ && (step == 0 || step >= 0x8000)) ++stats_.output_sequence_reorders;
    if (have_output_sequence_ && step > 1 && step < 0x8000)
      stats_.output_sequence_gaps += step - 1u;
    have_output_sequence_ = true;
    last_output_sequence_ = seq;
  }
  return e;
}

std::size_t FirmwareHost::get_feature(std::uint8_t report_id, std::span<std::uint8_t> out) {
  std::lock_guard lock(mutex_);
  return firmware_.get_feature(report_id, out);
}

protocol::Error FirmwareHost::set_feature(std::span<const std::uint8_t> bytes) {
  std::lock_guard lock(mutex_);
  advance_locked(realtime::monotonic_now_ns());
  return firmware_.set_feature(bytes);
}

void FirmwareHost::on_link_lost() {
  std::lock_guard lock(mutex_);
  advance_locked(realtime::monotonic_now_ns());
  firmware_.on_link_lost();
  ++stats_.link_losses;
  // A new connection starts a new output sequence.
  have_output_sequence_ = false;
}

std::optional<WatchdogTrip> FirmwareHost::current_watchdog_trip() {
  std::lock_guard lock(mutex_);
  return trip_;
}

FirmwareHostStats FirmwareHost::stats() {
  std::lock_guard lock(mutex_);
  FirmwareHostStats s = stats_;
  s.firmware = firmware_.stats();
  return s;
}

}  // namespace tsmh::usb_stack
