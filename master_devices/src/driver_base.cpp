#include "master_devices/driver_base.hpp"

#include <algorithm>
#include <cmath>

namespace tsmh::master_devices {

DriverBase::DriverBase(std::shared_ptr<const Clock> clock)
    : clock_(clock ? std::move(clock) : monotonic_clock()) {}

std::string DriverBase::last_error() const {
  {
    std::lock_guard lock(error_mutex_);
    if (!error_.empty()) return error_;
  }
  switch (const FaultCode f = fault_.load()) {
    case FaultCode::kNone:
      return "";
    case FaultCode::kHostRequested:
      return "fault raised by the host";
    default:
      return "fault: " + std::string(to_string(f));
  }
}

void DriverBase::set_error(const std::string& text) {
  std::lock_guard lock(error_mutex_);
  error_ = text;
}

bool DriverBase::clear_fault() {
  unlatch_fault();
  set_error("");
  return true;
}

void DriverBase::write_torque(const JointArray& tau_nm) noexcept {
  commands_.store(Command{tau_nm, clock_->now_ns(), true});
}

DeviceStatus DriverBase::status() const noexcept {
  if (!opened_.load()) return DeviceStatus::kClosed;
  if (fault_.load() != FaultCode::kNone) return DeviceStatus::kFault;
  if (!link_up_.load()) return DeviceStatus::kDisconnected;
  return DeviceStatus::kOk;
}

bool DriverBase::latch_fault(FaultCode code) noexcept {
  FaultCode expected = FaultCode::kNone;
  const bool latched = fault_.compare_exchange_strong(expected, code);
  enable_requested_.store(false);
  return latched;
}

void DriverBase::unlatch_fault() noexcept {
  enable_requested_.store(false);
  fault_.store(FaultCode::kNone);
}

DriverBase::Torque DriverBase::torque_to_send(const Command& cmd, std::int64_t now_ns,
                                              std::int64_t command_timeout_ns,
                                              bool allowed) const noexcept {
  Torque out;
  out.drive = allowed && status() == DeviceStatus::kOk && enable_requested_.load() && cmd.valid &&
              now_ns - cmd.t_ns <= command_timeout_ns;
  if (!out.drive) return out;
  for (std::size_t j = 0; j < spec_.dof && j < kMaxDof; ++j) {
    const double peak = spec_.peak_torque_nm[j];
    out.tau[j] = std::isfinite(cmd.tau[j]) ? std::clamp(cmd.tau[j], -peak, peak) : 0.0;
  }
  return out;
}

DeviceReading DriverBase::newest_reading(std::int64_t now_ns,
                                         std::int64_t fresh_bound_ns) noexcept {
  DeviceReading r;
  r.fresh = reading_reader_.fetch(r);
  r.status = status();
  r.fault = fault_.load();
  apply_reading_rules(r, now_ns, fresh_bound_ns, enable_requested_.load());
  return r;
}

}  // namespace tsmh::master_devices
