#include "master_devices/vendor_master.hpp"

#include <cmath>
#include <numbers>

#include "config/field_reader.hpp"

namespace tsmh::master_devices {

void MissingSdkMaster::open() {
  throw DeviceError(name_ + ": this build cannot drive it: " + missing_ +
                    ". Implement tsmh::master_devices::VendorMaster with its calls "
                    "(master_devices/include/master_devices/vendor_master.hpp) in a build that "
                    "links it; docs/adding-a-driver.md, \"A master whose SDK cannot ship\"");
}

namespace {

// For a pantograph, joint angles that put the handle in the middle of its
// workspace (elbows out, handle up); else the workspace's centre.
JointArray home_pose(const MasterProfile& p) {
  JointArray q{};
  if (p.kinematics.type == KinematicsType::kPantograph) {
    q[0] = 2.0;
    q[1] = 1.1;
    return q;
  }
  for (std::size_t k = 0; k < p.kinematics.joints; ++k)
    q[k] = 0.5 * (p.workspace_min[k] + p.workspace_max[k]);
  return q;
}

}  // namespace

SimulatedVendorMaster::SimulatedVendorMaster(const MasterProfile& profile, double rate_hz,
                                             double amplitude)
    : n_(profile.kinematics.joints),
      dt_(1.0 / rate_hz),
      amplitude_(amplitude),
      home_(home_pose(profile)),
      q_(home_) {}

bool SimulatedVendorMaster::read(JointArray& coordinates, std::uint32_t& buttons) {
  t_ += dt_;
  for (std::size_t j = 0; j < n_; ++j) {
    const double f = 0.2 + 0.1 * static_cast<double>(j);
    const double target = home_[j] + amplitude_ * std::sin(2.0 * std::numbers::pi * f * t_);
    const double hand = 3.0 * (target - q_[j]) - 0.2 * qd_[j];
    qd_[j] += dt_ * (hand + effort_[j] - 0.005 * qd_[j]) / 0.007;
    q_[j] += dt_ * qd_[j];
  }
  coordinates = q_;
  buttons = 1U;  // bit 0 (the profile's first button) held
  return true;
}

void SimulatedVendorMaster::zero_from_signal_handler() noexcept {
  for (double& e : effort_)
    e = 0.0;
}

std::string vendor_master_names() {
  return "simulated, novint-falcon, force-dimension, openhaptics";
}

std::unique_ptr<VendorMaster> make_vendor_master(std::string_view name,
                                                 const MasterProfile& profile, double rate_hz,
                                                 double amplitude) {
  if (name == "simulated")
    return std::make_unique<SimulatedVendorMaster>(profile, rate_hz, amplitude);
  if (name == "novint-falcon")
    return std::make_unique<MissingSdkMaster>(
        "novint-falcon",
        "the Falcon runs only with Novint's firmware, which may not be redistributed, loaded "
        "by Novint's SDK or by libnifalcon from a copy you obtain");
  if (name == "force-dimension")
    return std::make_unique<MissingSdkMaster>(
        "force-dimension", "Force Dimension's devices need their DHD/DRD SDK (proprietary)");
  if (name == "openhaptics")
    return std::make_unique<MissingSdkMaster>(
        "openhaptics",
        "Geomagic/3D Systems Touch devices need the OpenHaptics HD API (proprietary)");
  throw config::ConfigError(
      "'" + std::string(name) +
      "' is not a known vendor master (expected one of: " + vendor_master_names() + ")");
}

}  // namespace tsmh::master_devices
