#pragma once
// The slave's joint controller, one per joint, run once per control period.
//
// Inner loop: PD on the motor (input pulley) angle plus the measured tendon
// torque R (T1 - T3) as feedforward, so the motor follows its reference
// regardless of the tendon load.
//
// Compensation (the paper's Fig. 6 structure, after Do et al.'s backlash
// compensation): the motor reference is the joint reference plus
//  - a backlash-inverse feedforward c_hat * d: the motor leads by the
//    dead-band half-width on the side of the last motion, so the output does
//    not wait at reversals. The side d in [-1, 1] moves towards sign(r_dot)
//    in proportion to how far the reference moved (fully switched after
//    `switch_width_rad`), so it keeps its value while the reference rests
//    (the band is not re-crossed) and sensor-size jitter barely moves it;
//  - an adaptive law for c_hat driven by the joint-encoder error
//    (c_hat_dot = gamma * e * d, projected to [0, c_max]), so the width is
//    learned on line and follows sheath re-routing. It adapts only while the
//    reference moves: at rest the error is elastic lag under load, not backlash;
//  - proportional-integral correction of the joint error, which removes the
//    elastic lag under tissue load.
// Without a joint encoder (x_out NaN) only the feedforward with the initial
// width is applied.

#include "virtual_tissue_slave/sensors.hpp"

namespace tsmh::virtual_tissue_slave {

struct ControllerParams {
  double kp = 30.0;                    ///< motor angle stiffness, N m/rad
  double kd = 0.4;                     ///< motor damping, N m s/rad
  bool tension_feedforward = true;     ///< add the measured R (T1 - T3)
  double velocity_filter_hz = 150.0;   ///< low-pass on the motor velocity estimate
  bool compensation = true;            ///< false: motor reference = joint reference (baseline)
  double backlash_initial_rad = 0.11;  ///< initial half-width estimate c_hat(0), rad
  double backlash_max_rad = 0.3;       ///< projection bound for c_hat, rad
  double adapt_gain = 1.0;             ///< gamma, 1/s
  double adapt_velocity = 0.1;         ///< full adaptation above this reference speed, rad/s
  double switch_width_rad = 0.005;     ///< reference travel that switches the side d fully, rad
  double output_kp = 2.5;              ///< joint error to motor reference, rad/rad
  double output_ki = 30.0;             ///< integral of joint error, 1/s
  double integral_limit_rad = 1.5;     ///< anti-windup bound of the integral term, rad
};

/// Throws std::invalid_argument naming the bad field.
void validate(const ControllerParams& params);

class JointController {
 public:
  explicit JointController(const ControllerParams& params);
  /// Starts from rest at the measured state; clears filters and adaptation.
  void reset(const Measurement& m, double reference);
  /// One control period: returns the motor torque, N m. Does not allocate.
  double update(double reference, const Measurement& m, double radius_m, double dt);
  double motor_reference() const { return motor_ref_; }
  double backlash_estimate() const { return c_hat_; }
  double side() const { return side_; }  ///< d, the side of the dead band
  const ControllerParams& params() const { return params_; }

 private:
  ControllerParams params_;
  bool started_ = false;
  double last_ref_ = 0.0, side_ = 0.0;
  double last_x_in_ = 0.0, velocity_ = 0.0;
  double c_hat_ = 0.0, integral_ = 0.0, motor_ref_ = 0.0;
};

}  // namespace tsmh::virtual_tissue_slave
