#pragma once
// A master of any shape presented to the loop as a master with the slave's
// joints: wraps a driver's Device (its own joints) with the mapping layer
// (axis_mapping.hpp). read() turns the device's joint angles into the slave
// positions the master asks for (and their rates, through the Jacobian);
// write_torque() takes the slave joints' torques back through the Jacobian
// transpose to the device's joints, within the profile's limits in the
// device's own units. Everything else passes through. Allocation-free after
// construction, as the loop needs.

#include <memory>

#include "master_devices/axis_mapping.hpp"
#include "master_devices/device.hpp"

namespace tsmh::master_devices {

class MappedDevice final : public Device {
 public:
  /// `inner` reports `profile.kinematics.joints` joints in the profile's units.
  MappedDevice(std::unique_ptr<Device> inner, MasterProfile profile, const MappingConfig& mapping);

  /// The slave's joints: dof = the mapping's joint count; peak torque of
  /// slave joint i = the handle's force limit on its axis / |scale_i| (the
  /// most the profile lets the handle push back); position range = the
  /// workspace mapped onto it.
  const DeviceSpec& spec() const override { return spec_; }
  void open() override { inner_->open(); }
  void close() noexcept override { inner_->close(); }
  std::string last_error() const override { return inner_->last_error(); }
  bool clear_fault() override { return inner_->clear_fault(); }

  DeviceReading read(std::int64_t now_ns) noexcept override;
  void write_torque(const JointArray& tau_slave_nm) noexcept override;
  void set_enabled(bool on) noexcept override { inner_->set_enabled(on); }
  void raise_fault(FaultCode code) noexcept override { inner_->raise_fault(code); }
  DeviceStatus status() const noexcept override { return inner_->status(); }
  bool simulated_time() const noexcept override { return inner_->simulated_time(); }

  Device& inner() { return *inner_; }
  const MasterMapping& mapping() const { return mapping_; }

 private:
  std::unique_ptr<Device> inner_;
  MasterProfile profile_;
  MasterMapping mapping_;
  MappingConfig config_;
  DeviceSpec spec_;
  JointArray commanded_{};  // loop thread only
};

}  // namespace tsmh::master_devices
