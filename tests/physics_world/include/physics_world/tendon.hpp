#pragma once
// One tendon through its sheath as a chain of point masses joined by
// elastic segments. Each inner node rubs on the sheath with Coulomb friction
// bounded by mu times its normal force, and that normal force is the local
// tension times the sheath's wrap angle at the node (a tensioned cable on a
// curve presses on it with T dtheta). Nothing else is assumed: the capstan
// ratio exp(-mu wrap), the slip that spreads from the pulled end along the
// sheath (presliding), and the friction's growth with tension all emerge.
//
// Coordinates: u is each node's displacement along the tendon towards the
// proximal (motor) end, from the pretensioned rest state; node 0 is the
// proximal end, node n the distal end. Both ends are prescribed by the
// caller (the pulleys); the inner nodes are integrated.

#include <cstddef>
#include <vector>

namespace tsmh::physics_world {

struct TendonParams {
  int segments = 24;      ///< elastic segments (segments - 1 inner nodes)
  double length_m = 1.5;  ///< tendon length inside the sheath
  double ea_n = 9000.0;   ///< axial stiffness E A, N
  /// Mass of each inner node. 1 g is several times a steel cable's (a 1.5 m
  /// cable of 0.6 mm is ~3 g in all): heavier keeps the physics step
  /// longer, and the nodes' inertia still stays below a few mN at the
  /// motions here (23 g x 0.1 m/s^2), far below the load cells' noise.
  double node_mass_kg = 1e-3;
  /// Internal (material) damping, as the damping ratio of the chain's
  /// highest mode; it only keeps the chain from ringing between nodes.
  double damping_ratio = 0.3;
  double mu = 0.15;  ///< Coulomb coefficient tendon/sheath
  /// Normal force on each node that does not come from the tension (the
  /// tendon's bending stiffness pressing on the liner), N.
  double base_normal_n = 0.0;
  /// Viscous drag of each node against the sheath (lubricant), N s/m.
  double drag_n_s_per_m = 0.0;
  double pretension_n = 20.0;  ///< tension everywhere at rest, u = 0
};

/// Throws std::invalid_argument naming the bad field.
void validate(const TendonParams& params);

class Tendon {
 public:
  /// `wrap_rad[i]` is the sheath's bend angle at inner node i + 1 (segments
  /// - 1 values, each >= 0). Throws std::invalid_argument.
  Tendon(const TendonParams& params, std::vector<double> wrap_rad);

  /// Sets the ends (positions, m, and velocities, m/s) the next step starts from.
  void set_ends(double u_proximal, double v_proximal, double u_distal, double v_distal);
  /// Advances the inner nodes by dt (semi-implicit Euler; friction as a
  /// bounded impulse, so a node whose net force is below mu N sticks exactly).
  void step(double dt);

  /// Tension of segment i (1..segments), N, from the current state (>= 0: a
  /// tendon cannot push).
  double tension(int segment) const;
  double proximal_tension() const { return tension(1); }
  double distal_tension() const { return tension(segments_); }

  /// Multiplies every node's wrap (a re-routed sheath); 1 restores it.
  void set_wrap_scale(double scale) { wrap_scale_ = scale; }
  double total_wrap() const;  ///< rad, with the scale

  int segments() const { return segments_; }
  double stiffness() const { return k_; }  ///< one segment's, N/m
  double node_position(int i) const { return u_[static_cast<std::size_t>(i)]; }
  double node_velocity(int i) const { return v_[static_cast<std::size_t>(i)]; }
  /// Energy the sheath took out since construction (friction and drag), J (>= 0).
  double dissipated() const { return dissipated_; }
  /// Potential energy in the segments' stretch beyond the rest state, plus
  /// the inner nodes' kinetic energy, J.
  double stored_energy() const;
  /// Inner nodes that did not move in the last step (stuck to the sheath).
  int stuck_nodes() const { return stuck_; }

 private:
  TendonParams p_;
  int segments_;
  double k_, c_, inv_m_;
  std::vector<double> wrap_;
  double wrap_scale_ = 1.0;
  std::vector<double> u_, v_;  // nodes 0..segments
  std::vector<double> t_;      // segment tensions of the step, 1..segments
  double dissipated_ = 0.0;
  int stuck_ = 0;
};

}  // namespace tsmh::physics_world
