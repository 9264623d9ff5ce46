#pragma once
// Time-domain passivity for delayed teleoperation, per joint:
// the two-port observer of Ryu, Artigas et al. ("time domain passivity
// control for position-position teleoperation with delays"; the
// time-delay power network) and an impedance-type passivity controller at
// the master port.
//
// The communication channel is a two-port between the master port (the
// handle: master velocity in, rendered torque out) and the slave port (the
// slave joint: its motion out, the torque it reports in). All quantities are
// in master units: torques as rendered (after the force mapping), angles as
// master radians (slave angle / position scale). Energy flowing INTO the
// network:
//   master port: -F_m dq_m   (the operator pushes against the rendered torque)
//   slave port:  +F_s dx_s   (the tissue pushes the slave back)
// and each port's flow is split into what went in (E_in) and what came out
// (E_out). The channel is passive when everything that comes out at a port
// went in at the other, delayed:
//   W_M(n) = E_in_S(n - T_back) - E_out_M(n) >= 0   (master side)
//   W_S(n) = E_in_M(n - T_fwd) - E_out_S(n) >= 0    (slave side)
// The master knows E_in_S(n - T_back) exactly from the slave's own data as
// it arrives (SLAVE_STATE carries the slave's angle; the torque is the
// estimate rendered from it), so W_M needs no extra message. Whenever the
// torque about to be rendered would make W_M negative, the controller adds
// just the damping (bounded by max_damping) that keeps it at zero: nothing
// changes while W_M is positive. When the correction reverses the torque
// into a brake, the energy the brake absorbs is the controller's
// dissipation and is credited to W_M (Artigas et al. add the controller's
// dissipated energy to the observer the same way). The slave-side controller (on W_S) would
// run in the slave's node; here only W_S's formula is provided.
//
// Discrete accounting as in Ryu-Hannaford: the force of tick n times the
// displacement of tick n. Pure value type; O(1) per tick, no allocation.

namespace tsmh::haptics {

struct PassivityConfig {
  bool enabled = false;  ///< off by default until measured (docs/haptic-server.md)
  /// Bound on the controller's damping, N m s/rad: keeps the correction from
  /// becoming a stiff, chattering brake on encoder noise.
  double max_damping_nms_per_rad = 1.0;
  /// Bound on a brake, N m: when paying back a deficit reverses the torque
  /// against the motion, at most this much (bench_teleop_delay: +0.16 N m
  /// kicks on release at 100 ms without it, +0.02 with it; the hold is the
  /// same either way).
  double max_brake_nm = 0.02;
};

/// Throws std::invalid_argument naming the field (passivity.*).
void validate(const PassivityConfig& c);

/// Energy that went into and came out of one port, J (N m rad).
struct PortEnergy {
  double in = 0.0;
  double out = 0.0;
  /// `e` = energy into the network during one step (either sign).
  void add(double e) noexcept {
    if (e > 0.0)
      in += e;
    else
      out -= e;
  }
};

/// W_S: the slave-side observer, from the master's input energy as the slave
/// received it (delayed) and the slave port's output energy.
inline double slave_side_energy(double master_in_delayed, double slave_out) noexcept {
  return master_in_delayed - slave_out;
}

class PassivityChannel {
 public:
  PassivityChannel() : PassivityChannel(PassivityConfig{}) {}
  explicit PassivityChannel(const PassivityConfig& c);

  /// A new slave sample: `torque` the master-frame torque it reports, `angle`
  /// the slave joint angle in master radians. Non-finite values skip it.
  void slave_sample(double torque, double angle) noexcept;

  /// This tick's torque request for a master at `q`: returned unchanged
  /// while the controller is off or the observed energy stays >= 0, else
  /// with the damping that brings it back to 0 (bounded).
  double control(double q, double request, double dt_s) noexcept;

  /// The torque that was actually rendered this tick (after safety): the
  /// observer accounts with it.
  void commit(double rendered) noexcept;

  /// Start afresh (enabling, a slave clock jump): energies and positions.
  void reset() noexcept;

  /// W_M, J: E_in_S - E_out_M + what the controller's brake absorbed.
  double observed_energy() const noexcept { return slave_.in - master_.out + absorbed_; }
  double dissipated() const noexcept { return dissipated_; }  ///< by the controller, J
  bool active() const noexcept { return active_; }            ///< damping added this tick
  double damping() const noexcept { return damping_; }        ///< this tick's, N m s/rad
  const PortEnergy& master_port() const noexcept { return master_; }
  const PortEnergy& slave_port() const noexcept { return slave_; }

 private:
  PassivityConfig c_;
  PortEnergy master_, slave_;
  double q_prev_ = 0.0, dq_ = 0.0;
  bool have_q_ = false;
  double x_prev_ = 0.0, f_prev_ = 0.0;
  bool have_x_ = false;
  double dissipated_ = 0.0;
  double absorbed_ = 0.0;  // by the controller's brake (torque reversed against the motion)
  double damping_ = 0.0;
  bool active_ = false;
};

}  // namespace tsmh::haptics
