#pragma once
// The simulated operator: a hand holding the handle, modelled per joint as a
// mass-spring-damper that follows a scripted intention (scenarios.hpp) and
// reacts to the torque the device renders:
//
//   (J_hand + J_handle) q'' = k (q_int - q) + b (qd_int - qd) - c qd + tau_device
//
// k and b are the operator's arm impedance (how firmly the hand holds its
// intention), c the handle's own friction. Pressing into something stiff,
// the hand settles where the arm's spring balances the rendered torque, so
// with feedback on it moves less than with feedback off. Pure and
// deterministic: time advances only through step().

#include <cstddef>

#include "master_devices/scenarios.hpp"
#include "master_devices/types.hpp"

namespace tsmh::master_devices {

struct HandParams {
  double inertia_kgm2 = 0.005;        ///< hand + forearm, reflected to the joint
  double stiffness_nm_per_rad = 3.0;  ///< arm stiffness around the intention
  double damping_nms_per_rad = 0.2;   ///< arm damping (about 0.7 of critical with the defaults)
};

struct HandleParams {
  double inertia_kgm2 = 0.002;
  double damping_nms_per_rad = 0.005;
};

class SimulatedOperator {
 public:
  SimulatedOperator(Scenario scenario, std::size_t dof, HandParams hand = {},
                    HandleParams handle = {});

  /// Advances by dt_s with `device_torque` (N m per joint) applied to the
  /// handle throughout; internally sub-stepped for stability.
  void step(double dt_s, const JointArray& device_torque);

  /// Torque the hand applies to the handle in the current state (what an
  /// emulated mechanism receives as external torque).
  JointArray hand_torque() const;

  double time_s() const { return t_; }
  const JointArray& q() const { return q_; }
  const JointArray& qd() const { return qd_; }
  Intention intention() const { return intention_at(scenario_, t_, dof_); }
  const Scenario& scenario() const { return scenario_; }
  std::size_t dof() const { return dof_; }
  /// Resets time and state to the start of the scenario.
  void reset();

 private:
  Scenario scenario_;
  std::size_t dof_;
  HandParams hand_;
  HandleParams handle_;
  double t_ = 0.0;
  JointArray q_{};
  JointArray qd_{};
};

}  // namespace tsmh::master_devices
