#include "master_devices/console_device.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "realtime/enum_names.hpp"

namespace tsmh::master_devices {

namespace {
constexpr std::size_t kErrorCapacity = 512;

const char* firmware_fault_text(protocol::FirmwareFault f) {
  return realtime::enum_name<protocol::FirmwareFault::kSupply>(
             f,
             {"none", "over-current", "over-temperature", "encoder error", "supply out of range"},
             "unknown")
      .data();
}
}  // namespace

ConsoleSettings parse_console_settings(config::FieldReader& r) {
  ConsoleSettings s;
  s.path = r.get_string("path", "");
  s.serial = r.get_string("serial", "");
  s.reconnect_interval_ms = r.get_int("reconnect_interval_ms", s.reconnect_interval_ms);
  if (s.reconnect_interval_ms < 1) r.fail("reconnect_interval_ms", "must be >= 1");
  s.command_timeout_ms = r.get_int("command_timeout_ms", s.command_timeout_ms);
  if (s.command_timeout_ms < 1) r.fail("command_timeout_ms", "must be >= 1");
  if (r.has("stale_timeout_ms") && r.has("stale_periods"))
    r.fail("stale_periods", "give stale_timeout_ms or stale_periods, not both");
  if (r.has("stale_timeout_ms")) {
    s.stale_timeout_ms = r.get_int("stale_timeout_ms");
    if (s.stale_timeout_ms < 1) r.fail("stale_timeout_ms", "must be >= 1");
  }
  s.stale_periods = r.get_double("stale_periods", s.stale_periods);
  if (!(s.stale_periods >= 1.0)) r.fail("stale_periods", "must be >= 1");
  s.clock_tolerance_ppm = r.get_double("clock_tolerance_ppm", s.clock_tolerance_ppm);
  if (!(s.clock_tolerance_ppm >= 0.0 && s.clock_tolerance_ppm <= 100000.0))
    r.fail("clock_tolerance_ppm", "must be 0 .. 100000");
  s.velocity_cutoff_hz = r.get_double("velocity_cutoff_hz", s.velocity_cutoff_hz);
  if (!(s.velocity_cutoff_hz > 0.0)) r.fail("velocity_cutoff_hz", "must be > 0");
  s.workspace_margin_rad = r.get_double("workspace_margin_rad", s.workspace_margin_rad);
  if (!(s.workspace_margin_rad >= 0.0)) r.fail("workspace_margin_rad", "must be >= 0");
  s.max_bad_reports = static_cast<int>(r.get_int("max_bad_reports", s.max_bad_reports));
  if (s.max_bad_reports < 1) r.fail("max_bad_reports", "must be >= 1");
  s.wait_for_device = r.get_bool("wait_for_device", s.wait_for_device);
  return s;
}

ConsoleDevice::ConsoleDevice(std::string driver, DeviceProfile profile, ConsoleSettings settings,
                             std::shared_ptr<TransportProvider> provider,
                             std::shared_ptr<const Clock> clock)
    : DriverBase(std::move(clock)),
      driver_(std::move(driver)),
      profile_(std::move(profile)),
      settings_(std::move(settings)),
      provider_(std::move(provider)),
      device_clock_(settings_.clock_tolerance_ppm) {
  spec_ = spec_from_profile(profile_, driver_);
  fresh_bound_ns_ =
      settings_.stale_timeout_ms > 0
          ? settings_.stale_timeout_ms * 1'000'000LL
          : std::llround(settings_.stale_periods * 1e9 / std::max(1.0, spec_.nominal_rate_hz));
  if (profile_.joints.size() > protocol::kJoints) {
    throw DeviceError(profile_.source + ": profile '" + profile_.name + "' has " +
                      std::to_string(profile_.joints.size()) +
                      " joints; the console protocol carries " + std::to_string(protocol::kJoints));
  }
  error_.reserve(kErrorCapacity);
  for (std::size_t j = 0; j < profile_.joints.size(); ++j) {
    const JointProfile& jp = profile_.joints[j];
    velocity_[j] = VelocityEstimator(settings_.velocity_cutoff_hz);
    limiters_[j] = CurrentLimiter(jp.current_limit_continuous_a, jp.current_limit_peak_a,
                                  profile_.thermal_time_constant_s);
  }
}

ConsoleDevice::~ConsoleDevice() {
  close();
}

// ---- setup ----

void ConsoleDevice::connect() {
  const std::string id = usb_id_string(profile_.vendor_id, profile_.product_id);
  std::vector<TransportDeviceInfo> found =
      provider_->enumerate(profile_.vendor_id, profile_.product_id);
  auto chosen = std::find_if(found.begin(), found.end(), [&](const TransportDeviceInfo& d) {
    return (settings_.path.empty() || d.path == settings_.path) &&
           (settings_.serial.empty() || d.serial == settings_.serial);
  });
  if (chosen == found.end()) {
    std::string msg = driver_ + ": no " + profile_.name + " (" + id + ")";
    if (!settings_.path.empty()) msg += " at " + settings_.path;
    if (!settings_.serial.empty()) msg += " with serial " + settings_.serial;
    msg += " found via " + std::string(provider_->name());
    if (!found.empty()) {
      msg += "; present:";
      for (const auto& d : found)
        msg += " " + d.path + (d.serial.empty() ? "" : " (serial " + d.serial + ")");
    }
    throw DeviceError(msg);
  }

  std::unique_ptr<Transport> t;
  try {
    t = provider_->open(*chosen);
  } catch (const TransportError& e) {
    throw DeviceError(driver_ + ": cannot open " + chosen->path + ": " + e.what());
  }
  const std::string where = driver_ + ": " + chosen->path + ": ";

  // DEVICE_INFO must match the profile: a wrong profile means wrong angles and torques.
  std::array<std::uint8_t, protocol::kMaxReportSize> buf{};
  protocol::DeviceInfo info;
  try {
    const std::size_t n = t->get_feature(protocol::kDeviceInfoReportId, buf);
    const auto decoded = protocol::decode_device_info(std::span<const std::uint8_t>(buf.data(), n));
    if (!decoded.ok()) throw DeviceError(where + protocol::describe(decoded.error));
    info = decoded.value;
  } catch (const TransportError& e) {
    throw DeviceError(where + "reading DEVICE_INFO: " + e.what());
  }
  if (info.dof != profile_.joints.size()) {
    throw DeviceError(where + "device has " + std::to_string(info.dof) + " joints but profile " +
                      profile_.source + " describes " + std::to_string(profile_.joints.size()));
  }
  for (std::size_t j = 0; j < info.dof; ++j) {
    const JointProfile& jp = profile_.joints[j];
    const double device_cpr = info.counts_per_rev[j] / (2.0 * 3.14159265358979323846);
    if (std::abs(device_cpr - jp.counts_per_rad) > 0.005 * device_cpr) {
      throw DeviceError(where + profile_.source + ": joints[" + std::to_string(j) +
                        "].counts_per_rad " + std::to_string(jp.counts_per_rad) +
                        " disagrees with the device's " + std::to_string(info.counts_per_rev[j]) +
                        " counts/rev (" + std::to_string(device_cpr) + " counts/rad)");
    }
    if (jp.current_limit_peak_a * 1000.0 > info.max_current_ma[j] + 0.5) {
      throw DeviceError(where + profile_.source + ": joints[" + std::to_string(j) +
                        "].current_limit_peak_a " + std::to_string(jp.current_limit_peak_a) +
                        " A exceeds the device's " + std::to_string(info.max_current_ma[j]) +
                        " mA");
    }
  }
  spec_.nominal_rate_hz = info.nominal_rate_hz;
  // Freshness bound: a few of the device's own periods (it streams at the
  // rate it announces), unless given in ms.
  if (settings_.stale_timeout_ms <= 0)
    fresh_bound_ns_ = std::llround(settings_.stale_periods * 1e9 / info.nominal_rate_hz);

  // CALIBRATION: the firmware enforces our current limits and watchdog too.
  protocol::Calibration cal;
  cal.watchdog_ms = profile_.watchdog_ms;
  for (std::size_t j = 0; j < protocol::kJoints; ++j) {
    const bool used = j < profile_.joints.size();
    cal.direction[j] = static_cast<std::int8_t>(used ? profile_.joints[j].direction : 1);
    cal.zero_offset_counts[j] = used ? std::clamp(profile_.joints[j].zero_offset_counts,
                                                  protocol::kCountsMin, protocol::kCountsMax)
                                     : 0;
    cal.current_limit_ma[j] = used ? static_cast<std::uint16_t>(std::lround(
                                         profile_.joints[j].current_limit_peak_a * 1000.0))
                                   : 0;
  }
  try {
    const auto encoded = protocol::encode(cal, buf);
    if (!encoded.ok()) throw DeviceError(where + protocol::describe(encoded.error));
    t->set_feature(std::span<const std::uint8_t>(buf.data(), encoded.value));
    const std::size_t n = t->get_feature(protocol::kCalibrationReportId, buf);
    const auto back = protocol::decode_calibration(std::span<const std::uint8_t>(buf.data(), n));
    if (!back.ok())
      throw DeviceError(where + "reading back CALIBRATION: " + protocol::describe(back.error));
    if (!(back.value == cal))
      throw DeviceError(where + "the device did not keep the CALIBRATION we sent");
  } catch (const TransportError& e) {
    throw DeviceError(where + "writing CALIBRATION: " + e.what());
  }

  // A new session: the device comes back disabled, the I/O state starts over.
  set_enabled(false);
  have_previous_ = false;
  device_clock_.reset();
  bad_in_a_row_ = 0;
  for (auto& v : velocity_)
    v.reset();
  last_sent_ = {};
  active_ = t.get();
  link_up_ = true;
  try {
    t->start(*this);
  } catch (const TransportError& e) {
    link_up_ = false;
    active_ = nullptr;
    throw DeviceError(where + "starting the input stream: " + e.what());
  }

  // A link loss during start() has already set link_lost_; the supervisor
  // (the caller, or started after open()) tears this transport down then.
  std::lock_guard lock(mutex_);
  transport_ = std::move(t);
  connected_path_ = chosen->path;
}

void ConsoleDevice::open() {
  if (opened_) return;
  {
    std::lock_guard lock(mutex_);
    stopping_ = false;
    arrival_ = false;
  }
  try {
    connect();
  } catch (const DeviceError& e) {
    if (!settings_.wait_for_device) throw;
    set_error(std::string(e.what()) + " (waiting for it)");
  }
  provider_->set_arrival_callback([this] {
    std::lock_guard lock(mutex_);
    arrival_ = true;
    wake_.notify_all();
  });
  opened_ = true;
  supervisor_ = std::thread([this] { supervise(); });
}

void ConsoleDevice::close() noexcept {
  if (!opened_.exchange(false)) return;
  // Ask for one last zero-torque, disabled output report before stopping.
  set_enabled(false);
  const std::uint64_t sent = n_sent_.load();
  for (int i = 0; i < 100 && link_up_ && n_sent_.load() < sent + 2; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  provider_->set_arrival_callback({});
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
    wake_.notify_all();
  }
  if (supervisor_.joinable()) supervisor_.join();
  std::unique_ptr<Transport> t;
  {
    std::lock_guard lock(mutex_);
    t = std::move(transport_);
    connected_path_.clear();
  }
  if (t) t->stop();
  link_up_ = false;
  active_ = nullptr;
}

void ConsoleDevice::supervise() {
  std::unique_lock lock(mutex_);
  while (!stopping_) {
    wake_.wait_for(lock, std::chrono::milliseconds(settings_.reconnect_interval_ms),
                   [this] { return stopping_ || link_lost_ || arrival_; });
    if (stopping_) break;
    if (link_lost_) {
      // Tear down outside the lock: stop() waits for a running callback,
      // and callbacks (on_link_lost) take this lock.
      std::unique_ptr<Transport> t = std::move(transport_);
      connected_path_.clear();
      loss_reason_ = last_error();
      link_lost_ = false;
      lock.unlock();
      if (t) t->stop();
      t.reset();
      lock.lock();
    }
    arrival_ = false;
    if (!transport_) {
      lock.unlock();
      try {
        connect();
        n_reconnects_++;
        loss_reason_.clear();
      } catch (const std::exception& e) {
        set_error(loss_reason_.empty() ? e.what() : loss_reason_ + "; reconnecting: " + e.what());
      }
      lock.lock();
    }
  }
}

// ---- I/O context ----

void ConsoleDevice::on_input_report(std::span<const std::uint8_t> report,
                                    std::int64_t t_ns) noexcept {
  const auto decoded = protocol::decode_input(report);
  if (!decoded.ok()) {
    n_bad_++;
    std::array<char, 160> text{};
    set_error_fixed(protocol::describe(decoded.error, text));
    if (++bad_in_a_row_ >= settings_.max_bad_reports) {
      latch_fault(FaultCode::kBadReports, "too many malformed input reports in a row");
    }
    send_output(t_ns, 0.0, false);  // keep the firmware informed, but never drive on garbage
    return;
  }
  bad_in_a_row_ = 0;
  const protocol::InputReport& in = decoded.value;
  n_reports_++;

  double dt_s = 0.0;
  if (have_previous_) {
    const std::uint16_t step = protocol::sequence_delta(previous_sequence_, in.sequence);
    if (step > 1) n_lost_ += step - 1u;
    dt_s = static_cast<std::uint32_t>(in.device_time_us - previous_device_us_) * 1e-6;
  }
  have_previous_ = true;
  previous_sequence_ = in.sequence;
  previous_device_us_ = in.device_time_us;

  // Dated on the device's clock: a report read late (queued by the kernel
  // while this thread was starved, or the last ones before an unplug) is as
  // old as the device says, and one later than the freshness bound carries
  // no torque: read() tells the loop it is stale, so it must not drive.
  const DeviceClock::Sample when = device_clock_.map(in.device_time_us, t_ns);
  const bool late = when.late_ns > fresh_bound_ns_.load(std::memory_order_relaxed);
  if (late) n_late_++;

  DeviceReading r;
  r.t_ns = when.t_ns;
  r.sequence = ++reading_count_;
  r.dof = static_cast<std::uint32_t>(profile_.joints.size());
  for (std::size_t j = 0; j < profile_.joints.size(); ++j) {
    const JointProfile& jp = profile_.joints[j];
    r.q[j] = counts_to_rad(jp, in.counts[j]);
    r.qd[j] = velocity_[j].update(r.q[j], dt_s);
    const double m = settings_.workspace_margin_rad;
    if (r.q[j] < jp.position_min_rad - m || r.q[j] > jp.position_max_rad + m) {
      char text[160];
      std::snprintf(text, sizeof text,
                    "joint %zu at %.3f rad is outside its workspace [%.3f, %.3f] by more than %.3f "
                    "rad (wrong zero_offset_counts?)",
                    j, r.q[j], jp.position_min_rad, jp.position_max_rad, m);
      latch_fault(FaultCode::kWorkspace, text);
    }
  }
  if (in.status.fault) {
    char text[96];
    std::snprintf(text, sizeof text, "device reports a fault: %s", firmware_fault_text(in.fault));
    latch_fault(FaultCode::kDeviceReported, text);
  }
  r.buttons = in.buttons;
  r.enabled = in.status.torque_enabled;
  r.status = DeviceStatus::kOk;  // read() overrides with link and fault state

  send_output(t_ns, dt_s, !late);
  r.tau_commanded = last_sent_;
  readings_.store(r);
}

void ConsoleDevice::send_output(std::int64_t t_ns, double dt_s, bool allow_torque) noexcept {
  Command cmd;
  command_reader_.fetch(cmd);
  const Torque torque =
      torque_to_send(cmd, t_ns, settings_.command_timeout_ms * 1'000'000LL, allow_torque);

  protocol::OutputReport out;
  out.sequence = output_sequence_++;
  out.enable = torque.drive;
  out.clear_fault = clear_device_fault_.exchange(false);
  last_sent_ = {};
  for (std::size_t j = 0; j < profile_.joints.size(); ++j) {
    const JointProfile& jp = profile_.joints[j];
    const double amps = limiters_[j].limit(torque_to_current_a(jp, torque.tau[j]), dt_s);
    out.current_ma[j] = to_milliamps(amps);
    last_sent_[j] = current_to_torque_nm(jp, out.current_ma[j] * 1e-3);
  }
  std::array<std::uint8_t, protocol::kOutputReportSize> bytes{};
  const auto encoded = protocol::encode(out, bytes);
  if (encoded.ok() && active_ != nullptr && active_->write_output(bytes)) {
    n_sent_++;
  } else {
    n_failed_++;
  }
}

void ConsoleDevice::on_link_lost(const char* why) noexcept {
  link_up_ = false;
  n_disconnects_++;
  char text[192];
  std::snprintf(text, sizeof text, "link lost: %s", why);
  set_error_fixed(text);
  std::lock_guard lock(mutex_);
  link_lost_ = true;
  wake_.notify_all();
}

// ---- real-time path ----

// ---- faults and errors ----

void ConsoleDevice::latch_fault(FaultCode code, const char* text) noexcept {
  if (DriverBase::latch_fault(code)) set_error_fixed(text);
}

bool ConsoleDevice::clear_fault() {
  const FaultCode f = fault();
  if (f == FaultCode::kNone) return true;
  if (f == FaultCode::kDeviceReported) {
    // Ask the firmware to clear, then see whether it stays clear.
    clear_device_fault_ = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  unlatch_fault();
  // A cause that persists re-latches on the next reports.
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  if (fault() != FaultCode::kNone) return false;
  set_error("");
  return true;
}

void ConsoleDevice::set_error_fixed(const char* text) noexcept {
  // "hid /dev/hidraw3: <text>", within the reserved capacity (no allocation).
  std::lock_guard lock(error_mutex_);
  const std::string_view parts[] = {
      driver_, active_ != nullptr ? " " : "",
      active_ != nullptr ? std::string_view(active_->info().path) : "", ": ", text};
  error_.clear();
  for (std::string_view part : parts) {
    error_.append(part.substr(0, kErrorCapacity - 1 - std::min(error_.size(), kErrorCapacity - 1)));
  }
}

ConsoleStats ConsoleDevice::stats() const {
  return ConsoleStats{n_reports_, n_bad_,    n_lost_,        n_late_,
                      n_sent_,    n_failed_, n_disconnects_, n_reconnects_};
}

std::string ConsoleDevice::connected_path() const {
  std::lock_guard lock(mutex_);
  return connected_path_;
}

}  // namespace tsmh::master_devices
