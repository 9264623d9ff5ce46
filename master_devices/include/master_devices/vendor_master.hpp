#pragma once
// The vendor's calls for a master whose SDK or firmware cannot ship with
// this project (the Novint Falcon needs Novint's firmware blob; Force
// Dimension's and 3D Systems' devices need their SDKs): everything an
// adapter needs from the device, behind one small interface, so that the
// rest (kinematics, the mapping to the slave's joints, buttons by name,
// limits, the LCM link, watchdogs) is ours and tested without it.
// examples/external_master_adapter uses it (--vendor NAME).
//
// Adding a device: implement VendorMaster with the SDK's calls (in a build of
// your own that links the SDK), describe the device with a master profile
// (master_devices/profiles/masters/), and return it from your copy of
// make_vendor_master(). Until then its name here is a stub that refuses to run.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "master_devices/device.hpp"
#include "master_devices/master_profile.hpp"

namespace tsmh::master_devices {

class VendorMaster {
 public:
  virtual ~VendorMaster() = default;
  /// Connects. Throws DeviceError naming the device and the cause.
  virtual void open() = 0;
  /// One sample in the profile's coordinates (joint angles, rad; or the
  /// handle's position, m, for an SDK that solves its own kinematics) and
  /// the raw button word (bit b = the profile's button b). False: the device
  /// is gone.
  virtual bool read(JointArray& coordinates, std::uint32_t& buttons) = 0;
  /// Joint torques (N m), or handle forces (N) for identity kinematics;
  /// already within the profile's limits.
  virtual void write(const JointArray& effort) = 0;
  /// Zero effort from a signal handler: async-signal-safe. A real SDK's call
  /// rarely is: write a zero command prepared at start-up to a descriptor of
  /// the device's own, or leave it to the device's watchdog.
  virtual void zero_from_signal_handler() noexcept = 0;
  virtual void close() noexcept = 0;
};

/// A device this build cannot drive: open() throws, naming what is missing
/// and how to add it. Everything else is inert.
class MissingSdkMaster final : public VendorMaster {
 public:
  MissingSdkMaster(std::string name, std::string missing)
      : name_(std::move(name)), missing_(std::move(missing)) {}
  void open() override;
  bool read(JointArray&, std::uint32_t&) override { return false; }
  void write(const JointArray&) override {}
  void zero_from_signal_handler() noexcept override {}
  void close() noexcept override {}

 private:
  std::string name_, missing_;
};

/// A handle of the profile's joints (inertia, damping) moved by a hand that
/// sweeps each coordinate slowly by `amplitude` (device units) around a home
/// pose (the workspace's centre; for a pantograph, joint angles with the
/// handle mid-workspace), plus the effort written to it, stepped by 1 /
/// rate_hz per read(). Holds button bit 0. What the adapter runs without
/// hardware.
class SimulatedVendorMaster final : public VendorMaster {
 public:
  SimulatedVendorMaster(const MasterProfile& profile, double rate_hz, double amplitude);
  void open() override {}
  bool read(JointArray& coordinates, std::uint32_t& buttons) override;
  void write(const JointArray& effort) override { effort_ = effort; }
  void zero_from_signal_handler() noexcept override;
  void close() noexcept override { effort_ = {}; }
  const JointArray& effort() const { return effort_; }

 private:
  std::size_t n_;
  double dt_, amplitude_, t_ = 0.0;
  JointArray home_{}, q_{}, qd_{}, effort_{};
};

/// `simulated`, or a stub for a device whose SDK or firmware is not in this
/// build: `novint-falcon`, `force-dimension`, `openhaptics`. Throws
/// config::ConfigError naming the known names for another.
std::unique_ptr<VendorMaster> make_vendor_master(std::string_view name,
                                                 const MasterProfile& profile, double rate_hz,
                                                 double amplitude);
/// "simulated, novint-falcon, force-dimension, openhaptics"
std::string vendor_master_names();

}  // namespace tsmh::master_devices
