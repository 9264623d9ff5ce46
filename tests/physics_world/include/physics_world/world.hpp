#pragma once
// The whole joint: an antagonistic pair of tendons (tendon 1 pulls the joint
// positive, tendon 2 negative), each through a sheath of its own bend
// profile, between a position-controlled input pulley and a distal pulley
// with inertia that carries the tip's loads: a tissue contact (a
// spring-damper that only pushes, beyond a surface angle), a grasped object
// on the other side (likewise), and a slow external torque from the
// grasped tissue. Re-routing scales the sheaths' bends during a run.
//
// Independent of the estimator's friction models and of the virtual slave:
// no friction law is assumed beyond Coulomb at each node (tendon.hpp).

#include <cstdint>
#include <limits>
#include <vector>

#include "physics_world/tendon.hpp"

namespace tsmh::physics_world {

/// A sheath's bend, as the wrap angle at each inner node.
struct SheathRoute {
  std::vector<double> wrap_rad;  ///< per inner node, rad
};

/// Bends as smooth bumps of curvature along the sheath: each bend (centre as
/// a fraction of the length, width as a fraction, total angle, rad) spread
/// over the nodes. `straight_rad` is spread evenly (the sheath's gentle
/// overall curve).
struct Bend {
  double centre = 0.5, width = 0.1, angle_rad = 1.0;
};
SheathRoute make_route(int segments, const std::vector<Bend>& bends, double straight_rad);

/// Scales both sheaths' bends smoothly from 1 to the given factors, over
/// `ramp_s` from `at_s` (the endoscope bends). NaN: never.
struct Reroute {
  double at_s = std::numeric_limits<double>::quiet_NaN();
  double ramp_s = 1.0;
  double scale1 = 1.0, scale2 = 1.0;
};

struct TipParams {
  double radius_m = 0.01;       ///< both pulleys' radius R
  double inertia_kg_m2 = 1e-5;  ///< distal pulley and jaw
  double damping_n_m_s = 2e-3;  ///< joint viscous damping, N m s/rad
  // Tissue: pushes back beyond tissue_surface_rad (x_out above it).
  double tissue_surface_rad = 0.5;
  double tissue_stiffness = 0.5;   ///< N m/rad
  double tissue_stiffening = 4.0;  ///< N m/rad^3 (cubic term: tissue stiffens)
  double tissue_damping = 0.01;    ///< N m s/rad, only while indented
  // A grasped object: pushes back below grasp_surface_rad.
  double grasp_surface_rad = -0.7;
  double grasp_stiffness = 1.0;  ///< N m/rad
  double grasp_damping = 0.01;   ///< N m s/rad
  /// Peak of the slow external torque the grasped tissue applies, N m.
  double external_peak_n_m = 0.04;
};

struct WorldParams {
  TendonParams tendon1, tendon2;
  SheathRoute route1, route2;
  TipParams tip;
  Reroute reroute;
  int substeps = 40;       ///< physics steps per 1 ms sample
  std::uint64_t seed = 0;  ///< the sheath's seed (random_world), 0 when built by hand
};

/// A sheath drawn from `seed`: friction coefficient, stiffness, lengths,
/// pretension, two unequal bend profiles, the tip's tissue and grasp.
/// Ranges in world.cpp; the same seed always gives the same world.
WorldParams random_world(std::uint64_t seed);

/// Throws std::invalid_argument naming the bad field.
void validate(const WorldParams& params);

/// Physics steps per 1 ms sample that keep the stiffest tendon's highest
/// mode stable with a margin (what random_world() sets).
int stable_substeps(const WorldParams& params);

/// The joint's true state at one instant.
struct TipState {
  double x_in = 0.0, xd_in = 0.0, xdd_in = 0.0;   ///< input pulley (prescribed)
  double x_out = 0.0, xd_out = 0.0;               ///< distal pulley
  double T1 = 0.0, T2 = 0.0, T3 = 0.0, T4 = 0.0;  ///< N: T1/T3 proximal, T2/T4 distal
  double tissue_torque = 0.0, grasp_torque = 0.0, external_torque = 0.0;  ///< N m on the tip
  bool in_contact() const { return tissue_torque > 0.0 || grasp_torque > 0.0; }
};

class World {
 public:
  /// Throws std::invalid_argument for bad parameters.
  explicit World(const WorldParams& params);

  /// Advances by dt with the input pulley at x_in (rad) moving at xd_in and
  /// the external torque on the tip given (N m).
  void step(double dt, double x_in, double xd_in, double xdd_in, double external_torque);
  /// Applies the re-route's scale for time t (s).
  void apply_route(double t);

  TipState state() const;
  const Tendon& tendon1() const { return t1_; }
  const Tendon& tendon2() const { return t2_; }
  const WorldParams& params() const { return p_; }
  /// Holds the distal pulley fixed where it is (a clamped tip), for tests.
  void clamp_tip(bool clamped) {
    clamped_ = clamped;
    if (clamped) xd_out_ = 0.0;
  }

 private:
  double tissue(double x, double xd) const;
  double grasp(double x, double xd) const;
  WorldParams p_;
  Tendon t1_, t2_;
  double x_in_ = 0.0, xd_in_ = 0.0, xdd_in_ = 0.0;
  double x_out_ = 0.0, xd_out_ = 0.0;
  double external_ = 0.0;
  bool clamped_ = false;
};

}  // namespace tsmh::physics_world
