#include "master_devices/mapped_device.hpp"

#include <algorithm>
#include <cmath>

namespace tsmh::master_devices {

MappedDevice::MappedDevice(std::unique_ptr<Device> inner, MasterProfile profile,
                           const MappingConfig& mapping)
    : inner_(std::move(inner)),
      profile_(std::move(profile)),
      mapping_(profile_, mapping),
      config_(mapping) {
  const DeviceSpec& in = inner_->spec();
  spec_.model = in.model;
  spec_.driver = in.driver;
  spec_.dof = static_cast<std::uint32_t>(config_.slave_joints);
  spec_.nominal_rate_hz = in.nominal_rate_hz;
  spec_.has_calibrate_button = config_.buttons.calibrate >= 0 || in.has_calibrate_button;
  for (std::size_t i = 0; i < config_.slave_joints; ++i) {
    const AxisMapConfig& a = config_.axes[i];
    const auto k = static_cast<std::size_t>(a.master_axis);
    spec_.joint_names[i] = profile_.axis_names[k];
    const double peak = profile_.force_limit[k] / std::abs(a.scale);
    spec_.peak_torque_nm[i] = peak;
    spec_.max_continuous_torque_nm[i] = peak;
    // v = scale (x - centre) + offset over the workspace's extent on axis k.
    const double centre = 0.5 * (profile_.workspace_min[k] + profile_.workspace_max[k]);
    const double v1 = a.scale * (profile_.workspace_min[k] - centre) + a.offset;
    const double v2 = a.scale * (profile_.workspace_max[k] - centre) + a.offset;
    spec_.position_min_rad[i] = std::min(v1, v2);
    spec_.position_max_rad[i] = std::max(v1, v2);
  }
}

DeviceReading MappedDevice::read(std::int64_t now_ns) noexcept {
  const DeviceReading in = inner_->read(now_ns);
  DeviceReading r = in;
  r.dof = spec_.dof;
  r.q = {};
  r.qd = {};
  const bool valid = in.sequence > 0 && mapping_.update(in.q, 0U);
  r.q = mapping_.slave_position();
  if (valid && !mapping_.buttons().clutch) {
    // v_i = scale_i x_k + offset_i, so dv_i/dt = scale_i (J qd)_k.
    JointArray x{};
    Jacobian J{};
    if (forward_kinematics(profile_.kinematics, in.q, x, J)) {
      for (std::size_t i = 0; i < config_.slave_joints; ++i) {
        const auto k = static_cast<std::size_t>(config_.axes[i].master_axis);
        double xd = 0.0;
        for (std::size_t j = 0; j < profile_.kinematics.joints; ++j)
          xd += J[k][j] * in.qd[j];
        r.qd[i] = config_.axes[i].scale * xd;
      }
    }
  }
  // The device's own buttons, or the mapping's roles for them (a device
  // without a dead-man switch is `dead_man: held` in its mapping).
  const Buttons b = mapping_.buttons();
  r.buttons.dead_man = in.buttons.dead_man || b.dead_man;
  r.buttons.e_stop = in.buttons.e_stop || b.e_stop;
  r.buttons.clutch = in.buttons.clutch || b.clutch;
  r.buttons.calibrate = in.buttons.calibrate || b.calibrate;
  r.tau_commanded = in.status == DeviceStatus::kOk && in.enabled ? commanded_ : JointArray{};
  return r;
}

void MappedDevice::write_torque(const JointArray& tau_slave) noexcept {
  JointArray t{};
  for (std::size_t i = 0; i < config_.slave_joints; ++i)
    t[i] = std::isfinite(tau_slave[i])
               ? std::clamp(tau_slave[i], -spec_.peak_torque_nm[i], spec_.peak_torque_nm[i])
               : 0.0;
  commanded_ = t;
  inner_->write_torque(mapping_.joint_torques(t));
}

}  // namespace tsmh::master_devices
