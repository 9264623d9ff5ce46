#include "master_devices/simulated_operator.hpp"

#include <algorithm>
#include <cmath>

namespace tsmh::master_devices {

SimulatedOperator::SimulatedOperator(Scenario scenario, std::size_t dof, HandParams hand,
                                     HandleParams handle)
    : scenario_(std::move(scenario)), dof_(std::min(dof, kMaxDof)), hand_(hand), handle_(handle) {
  reset();
}

void SimulatedOperator::reset() {
  t_ = 0.0;
  const Intention in = intention_at(scenario_, 0.0, dof_);
  q_ = in.q;  // the hand starts where it wants to be, at rest
  qd_ = {};
}

JointArray SimulatedOperator::hand_torque() const {
  const Intention in = intention_at(scenario_, t_, dof_);
  JointArray tau{};
  for (std::size_t j = 0; j < dof_; ++j) {
    tau[j] = hand_.stiffness_nm_per_rad * (in.q[j] - q_[j]) +
             hand_.damping_nms_per_rad * (in.qd[j] - qd_[j]);
  }
  return tau;
}

void SimulatedOperator::step(double dt_s, const JointArray& device_torque) {
  if (!(dt_s > 0.0)) return;
  // Semi-implicit Euler; 0.2 ms sub-steps keep it stable for rendered
  // stiffness far beyond what a console can display.
  const int substeps = std::max(1, static_cast<int>(std::ceil(dt_s / 2.0e-4)));
  const double h = dt_s / substeps;
  const double inertia = hand_.inertia_kgm2 + handle_.inertia_kgm2;
  for (int s = 0; s < substeps; ++s) {
    const JointArray tau_hand = hand_torque();
    for (std::size_t j = 0; j < dof_; ++j) {
      const double tau_dev = std::isfinite(device_torque[j]) ? device_torque[j] : 0.0;
      const double tau = tau_hand[j] + tau_dev - handle_.damping_nms_per_rad * qd_[j];
      qd_[j] += h * tau / inertia;
      q_[j] += h * qd_[j];
    }
    t_ += h;
  }
}

}  // namespace tsmh::master_devices
