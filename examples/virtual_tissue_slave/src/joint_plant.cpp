#include "virtual_tissue_slave/joint_plant.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "field_checks.hpp"

namespace tsmh::virtual_tissue_slave {
namespace {

const JointParams& validated(const JointParams& p) {
  const FieldChecks check("joint '" + p.name + "':");
  check.positive(p.radius_m, "radius_m");
  check.positive(p.input_inertia, "input_inertia");
  check.positive(p.output_inertia, "output_inertia");
  check.positive(p.motor_torque_limit, "motor_torque_limit");
  check.non_negative(p.input_damping, "input_damping");
  check.non_negative(p.output_damping, "output_damping");
  validate(p.tissue);
  return p;
}

ChainFriction chain_friction(const FrictionEffects& e, const TendonParams& t, double radius) {
  ChainFriction f;
  f.capstan = e.capstan;
  // `viscous` is N of total friction (both tendons) per rad/s at the input:
  // spread it over the interior nodes of both tendons, tendon speed = R xd.
  f.viscous_n_s_per_m = e.viscous / (2.0 * (t.segments - 1) * radius);
  return f;
}

}  // namespace

JointPlant::JointPlant(const JointParams& params)
    : params_(validated(params)),
      chain1_(params.tendon1),
      chain2_(params.tendon2),
      base_wrap1_(params.tendon1.wrap_rad),
      base_wrap2_(params.tendon2.wrap_rad) {
  update_truth();
}

void JointPlant::set_wraps(double wrap1_rad, double wrap2_rad) {
  base_wrap1_ = wrap1_rad;
  base_wrap2_ = wrap2_rad;
  update_wraps();
}

void JointPlant::set_effects(const FrictionEffects& effects) {
  if (!std::isfinite(effects.viscous) || effects.viscous < 0)
    throw std::invalid_argument("effect 'viscous' must be >= 0");
  if (!std::isfinite(effects.wrap_position_gain))
    throw std::invalid_argument("effect 'position' must be finite");
  effects_ = effects;
  chain1_.set_friction(chain_friction(effects, params_.tendon1, params_.radius_m));
  chain2_.set_friction(chain_friction(effects, params_.tendon2, params_.radius_m));
  update_wraps();
}

void JointPlant::set_tissue(const TissueParams& tissue) {
  validate(tissue);
  params_.tissue = tissue;
  update_truth();
}

void JointPlant::update_wraps() {
  const double scale = std::max(0.0, 1.0 + effects_.wrap_position_gain * x_in_);
  chain1_.set_wrap(base_wrap1_ * scale);
  chain2_.set_wrap(base_wrap2_ * scale);
}

void JointPlant::step(double motor_torque, double dt) {
  const double r = params_.radius_m;
  motor_torque_ = std::clamp(motor_torque, -params_.motor_torque_limit, params_.motor_torque_limit);
  const double tau_in = r * (chain1_.proximal_tension() - chain2_.proximal_tension());
  const double tau_out = r * (chain1_.distal_tension() - chain2_.distal_tension());
  const ContactState c = contact(params_.tissue, x_out_, v_out_);

  // Semi-implicit Euler: velocities first (pulley damping implicit, so any
  // damping is stable), then positions with the new velocities.
  const double j_in = params_.input_inertia;
  const double j_out = params_.output_inertia;
  const double v_in_old = v_in_;
  v_in_ =
      (v_in_ + dt * (motor_torque_ - tau_in) / j_in) / (1.0 + dt * params_.input_damping / j_in);
  v_out_ =
      (v_out_ + dt * (tau_out - c.torque_nm) / j_out) / (1.0 + dt * params_.output_damping / j_out);
  a_in_ = (v_in_ - v_in_old) / dt;
  const double dx_in = dt * v_in_;
  const double dx_out = dt * v_out_;
  x_in_ += dx_in;
  x_out_ += dx_out;

  energy_.motor_work += motor_torque_ * dx_in;
  energy_.damping_dissipated +=
      params_.input_damping * v_in_ * dx_in + params_.output_damping * v_out_ * dx_out;
  energy_.tissue_work += c.torque_nm * dx_out;

  if (effects_.wrap_position_gain != 0.0) update_wraps();
  const ChainSolveInfo i1 = chain1_.solve(r * x_in_, r * x_out_, dt);
  const ChainSolveInfo i2 = chain2_.solve(-r * x_in_, -r * x_out_, dt);
  energy_.friction_dissipated += i1.dissipated_j + i2.dissipated_j;
  fallback_solves_ += (i1.used_fallback ? 1 : 0) + (i2.used_fallback ? 1 : 0);
  update_truth();
}

double JointPlant::stored_energy() const {
  return 0.5 * params_.input_inertia * v_in_ * v_in_ +
         0.5 * params_.output_inertia * v_out_ * v_out_ + chain1_.elastic_energy() +
         chain2_.elastic_energy();
}

void JointPlant::update_truth() {
  const double r = params_.radius_m;
  truth_.x_in = x_in_;
  truth_.xd_in = v_in_;
  truth_.xdd_in = a_in_;
  truth_.x_out = x_out_;
  truth_.xd_out = v_out_;
  truth_.T1 = chain1_.proximal_tension();
  truth_.T2 = chain1_.distal_tension();
  truth_.T3 = chain2_.proximal_tension();
  truth_.T4 = chain2_.distal_tension();
  truth_.tau_in = r * (truth_.T1 - truth_.T3);
  truth_.tau_out = r * (truth_.T2 - truth_.T4);
  truth_.friction = (truth_.tau_in - truth_.tau_out) / r;
  truth_.motor_torque = motor_torque_;
  truth_.contact = contact(params_.tissue, x_out_, v_out_);
}

}  // namespace tsmh::virtual_tissue_slave
