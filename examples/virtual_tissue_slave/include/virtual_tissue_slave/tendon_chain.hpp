#pragma once
// One tendon inside its sheath, as a chain of lumped elastic segments whose
// interior nodes rub on the sheath with Coulomb friction (the capstan law in
// discrete form). The tendon is massless: a 1.5 m tendon carries axial waves
// in well under a millisecond, so at the plant's time scales its shape is the
// quasi-static equilibrium reached from the previous shape. That makes the
// friction rate-independent and the stick/slip treatment exact: each node
// either stays exactly where it was (stick, friction inside its cone) or moves
// with the friction exactly at its bound, opposing the motion (slip).
//
// Coordinates: s_i is the displacement of node i along the sheath, positive
// towards the proximal (motor) end. Node 0 is the tendon's attachment on the
// input pulley, node N on the output pulley; nodes 1..N-1 lie in the sheath.
// Segment j (1..N) joins nodes j-1 and j; its tension is
// T_j = max(0, P + k (s_{j-1} - s_j)), with P the pretension and k = EA/(L/N).

#include <cstdint>
#include <vector>

namespace tsmh::virtual_tissue_slave {

struct TendonParams {
  double length_m = 1.5;         ///< sheath length, m
  double stiffness_ea_n = 4300;  ///< effective axial stiffness EA (tendon + sheath), N
  double pretension_n = 20.0;    ///< tension at the assembly reference shape, N
  double mu = 0.1;               ///< tendon-sheath Coulomb coefficient
  double wrap_rad = 2.5;         ///< total sheath wrap angle (integral of |curvature|), rad
  int segments = 16;             ///< lumped segments N (>= 2)
};

/// Effects that change the friction law at the nodes, for model-gap experiments.
struct ChainFriction {
  double viscous_n_s_per_m = 0.0;  ///< per node viscous drag against the sheath, N s/m
  bool capstan = true;  ///< false: normal force from the pretension only (load-independent)
};

/// Outcome of one quasi-static solve, for diagnostics and tests.
struct ChainSolveInfo {
  int iterations = 0;          ///< active-set iterations used
  bool used_fallback = false;  ///< the active set did not settle; projected Gauss-Seidel finished
  double dissipated_j = 0.0;   ///< energy dissipated at the nodes in this solve, J (>= 0)
};

class TendonChain {
 public:
  /// Throws std::invalid_argument naming the bad field.
  explicit TendonChain(const TendonParams& params);

  /// Total wrap angle of the sheath, spread uniformly over the interior nodes.
  /// May change at any time (the endoscope bends); takes effect at the next solve.
  void set_wrap(double wrap_rad);
  double wrap() const { return wrap_rad_; }
  void set_friction(const ChainFriction& friction) { friction_ = friction; }

  /// Moves the two ends to s_proximal / s_distal (m) and finds the new
  /// equilibrium from the current shape. `dt` only matters for viscous drag.
  /// Does not allocate.
  ChainSolveInfo solve(double s_proximal, double s_distal, double dt);

  double proximal_tension() const { return tension_[1]; }        ///< T of segment 1, N
  double distal_tension() const { return tension_[segments_]; }  ///< T of segment N, N
  /// Total sheath friction on this tendon, proximal minus distal tension, N.
  double friction_force() const { return proximal_tension() - distal_tension(); }
  double tension(int segment) const { return tension_[static_cast<std::size_t>(segment)]; }
  double node_position(int node) const { return s_[static_cast<std::size_t>(node)]; }
  /// -1 sliding distally, 0 stuck, +1 sliding proximally, for interior nodes 1..N-1.
  int node_regime(int node) const { return regime_[static_cast<std::size_t>(node)]; }
  int segments() const { return segments_; }
  /// Elastic energy stored in the segments relative to the reference shape, J.
  double elastic_energy() const;
  const TendonParams& params() const { return params_; }

 private:
  double raw_tension(int segment) const;
  double node_bound(int node) const;  // Coulomb bound mu*N at a node, from current tensions
  bool solve_active_set(double dt, int& iterations);
  void solve_projected_gauss_seidel(double dt);
  void refresh_tensions();

  TendonParams params_;
  ChainFriction friction_;
  int segments_;
  double k_;  // segment stiffness, N/m
  double wrap_rad_ = 0.0;
  double half_mu_dtheta_ = 0.0;  // a = mu * dTheta / 2 per interior node
  std::vector<double> s_, s_prev_, tension_;
  std::vector<int> regime_;
  std::vector<std::uint8_t> taut_;
  std::vector<double> lower_, diag_, upper_, rhs_;  // tridiagonal workspace
};

}  // namespace tsmh::virtual_tissue_slave
