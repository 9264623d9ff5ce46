#pragma once
// One slave joint: a motor-side input pulley driving an output pulley through a
// pair of tendon-sheath mechanisms (paper Fig. 2a), plus tissue at the tool.
// Tendon 1 runs in sheath 01 (proximal tension T1, distal T2), tendon 2 in
// sheath 02 (T3 proximal, T4 distal). A positive input angle winds tendon 1 on
// the input pulley, so tau_in = R (T1 - T3), tau_out = R (T2 - T4).

#include <string>

#include "virtual_tissue_slave/tendon_chain.hpp"
#include "virtual_tissue_slave/tissue.hpp"

namespace tsmh::virtual_tissue_slave {

struct JointParams {
  std::string name = "joint";
  double radius_m = 0.01;           ///< input and output pulley radius R, m
  TendonParams tendon1;             ///< in sheath 01
  TendonParams tendon2;             ///< in sheath 02
  double input_inertia = 4e-4;      ///< motor rotor + gearhead + input pulley, reflected, kg m^2
  double input_damping = 2e-3;      ///< motor-side viscous loss, N m s/rad
  double motor_torque_limit = 3.0;  ///< at the input pulley, N m
  double output_inertia = 5e-6;     ///< output pulley and link, kg m^2
  double output_damping = 5e-3;     ///< joint bearing loss, N m s/rad
  TissueParams tissue;
};

/// Hidden effects on the friction, switchable for model-gap experiments.
struct FrictionEffects {
  double viscous = 0.0;  ///< extra sheath drag: N of total friction per rad/s of input sliding
  bool capstan = true;   ///< false: friction independent of the transmitted load
  /// Position dependence: each sheath's wrap becomes wrap * (1 + gain * x_in).
  double wrap_position_gain = 0.0;
};

/// Everything true about the joint at one instant (no sensor effects).
struct JointTruth {
  double x_in = 0.0, xd_in = 0.0, xdd_in = 0.0;   ///< input pulley angle, rad (and derivatives)
  double x_out = 0.0, xd_out = 0.0;               ///< output (joint) angle, rad
  double T1 = 0.0, T2 = 0.0, T3 = 0.0, T4 = 0.0;  ///< tendon tensions at the sheath ends, N
  double tau_in = 0.0;                            ///< R (T1 - T3), N m
  double tau_out = 0.0;                           ///< R (T2 - T4), N m: the true distal torque
  double friction = 0.0;                          ///< (tau_in - tau_out) / R, N
  double motor_torque = 0.0;                      ///< applied after saturation, N m
  ContactState contact;
};

/// Energy bookkeeping since construction, J.
struct JointEnergy {
  double motor_work = 0.0;           ///< work done by the motor torque
  double friction_dissipated = 0.0;  ///< at the sheath (friction and drag), >= 0
  double damping_dissipated = 0.0;   ///< motor and joint viscous losses
  double tissue_work = 0.0;          ///< work done on the tissue by the tool
};

class JointPlant {
 public:
  /// Throws std::invalid_argument naming the bad field.
  explicit JointPlant(const JointParams& params);

  /// Advances the physics by dt (s) with `motor_torque` (N m, saturated to the
  /// limit) at the input pulley. Semi-implicit Euler for the pulleys, exact
  /// quasi-static equilibrium for the tendons. Does not allocate.
  void step(double motor_torque, double dt);

  /// Changes the sheaths' total wrap angles now (the endoscope bends).
  void set_wraps(double wrap1_rad, double wrap2_rad);
  void set_effects(const FrictionEffects& effects);
  void set_tissue(const TissueParams& tissue);

  const JointTruth& truth() const { return truth_; }
  const JointEnergy& energy() const { return energy_; }
  const JointParams& params() const { return params_; }
  const TendonChain& tendon1() const { return chain1_; }
  const TendonChain& tendon2() const { return chain2_; }
  /// Kinetic + tendon elastic + tissue elastic energy, J (tissue part up to
  /// the current indentation).
  double stored_energy() const;
  /// Solves that needed the slow fallback (should stay 0).
  long fallback_solves() const { return fallback_solves_; }

 private:
  void update_wraps();
  void update_truth();

  JointParams params_;
  FrictionEffects effects_;
  TendonChain chain1_, chain2_;
  double base_wrap1_, base_wrap2_;
  double x_in_ = 0.0, v_in_ = 0.0, a_in_ = 0.0, x_out_ = 0.0, v_out_ = 0.0;
  double motor_torque_ = 0.0;
  JointTruth truth_;
  JointEnergy energy_;
  long fallback_solves_ = 0;
};

}  // namespace tsmh::virtual_tissue_slave
