#pragma once
// The one interface every master device driver implements.
//
// Two kinds of callers: setup code (open, close, spec, last_error,
// clear_fault) which may block and allocate, and the real-time loop (read,
// write_torque, set_enabled, raise_fault, status) which must never block,
// allocate or lock. Drivers that talk to hardware run their own I/O thread and
// exchange values with the loop through LatestValue cells.

#include <cstdint>
#include <stdexcept>
#include <string>

#include "master_devices/types.hpp"

namespace tsmh::master_devices {

/// A device could not be created or opened. The message names the device and the cause.
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class Device {
 public:
  Device() = default;
  virtual ~Device() = default;
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;

  // ---- setup: may block, allocate, throw ----

  /// What the device can do. Valid after construction; open() may refine it
  /// from what the device reports.
  virtual const DeviceSpec& spec() const = 0;

  /// Connects and starts streaming. Throws DeviceError naming what failed.
  /// Torque output starts disabled.
  virtual void open() = 0;

  /// Zeroes torque, stops streaming, releases the device. Idempotent.
  virtual void close() noexcept = 0;

  /// The most recent error or fault, in words ("" when none).
  virtual std::string last_error() const = 0;

  /// Leaves kFault when the cause is gone; returns false (still kFault) otherwise.
  /// Torque stays disabled after a cleared fault until set_enabled(true).
  virtual bool clear_fault() = 0;

  // ---- real-time path: never block, allocate or lock ----

  /// The newest reading. `now_ns` is the caller's clock: CLOCK_MONOTONIC for
  /// real-time use (drivers compare it with the sample time to detect a
  /// silent device), or simulated time for devices in simulated-time mode,
  /// which advance their world up to `now_ns` (non-decreasing) inside read().
  virtual DeviceReading read(std::int64_t now_ns) noexcept = 0;

  /// Joint torque command, N m, one entry per joint (entries >= dof ignored).
  /// Drivers clamp to the spec's peak torque and apply zero while disabled,
  /// disconnected or faulted. The value holds until the next call; hardware
  /// drivers zero it when calls stop (the loop died).
  virtual void write_torque(const JointArray& tau_nm) noexcept = 0;

  /// Enables or disables torque output. After a disconnect/reconnect or a
  /// cleared fault the device comes back disabled.
  virtual void set_enabled(bool on) noexcept = 0;

  /// Latches kFault (torque zero) for a reason the host found, e.g. its own safety check.
  virtual void raise_fault(FaultCode code) noexcept = 0;

  /// Current status without consuming a reading.
  virtual DeviceStatus status() const noexcept = 0;

  /// True when read() advances a simulated world to its `now_ns` argument
  /// (deterministic tests, faster than real time); false for real time.
  virtual bool simulated_time() const noexcept { return false; }
};

}  // namespace tsmh::master_devices
