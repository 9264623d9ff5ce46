#include "physics_world/world.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace tsmh::physics_world {

namespace {

void require(bool ok, const std::string& field, const char* what) {
  if (!ok) throw std::invalid_argument("world." + field + ": " + what);
}

bool finite_positive(double v) {
  return std::isfinite(v) && v > 0.0;
}

// 0 -> 1 with zero slope at both ends (quintic smoothstep).
double smoothstep(double s) {
  s = std::clamp(s, 0.0, 1.0);
  return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
}

}  // namespace

int stable_substeps(const WorldParams& w) {
  double dt_max = 1.0;
  for (const TendonParams* t : {&w.tendon1, &w.tendon2}) {
    // Semi-implicit Euler on the chain's highest mode (omega^2 = 4 k / m,
    // damping ratio zeta) is stable for dt < (2 / omega) (sqrt(1 + zeta^2) - zeta).
    const double k = t->ea_n * t->segments / t->length_m;
    const double omega = 2.0 * std::sqrt(k / t->node_mass_kg);
    const double z = t->damping_ratio;
    dt_max = std::min(dt_max, 2.0 / omega * (std::sqrt(1.0 + z * z) - z));
  }
  // With a margin of 0.6, in whole steps per 1 ms sample.
  return std::max(1, static_cast<int>(std::ceil(1e-3 / (0.6 * dt_max))));
}

SheathRoute make_route(int segments, const std::vector<Bend>& bends, double straight_rad) {
  if (segments < 2) throw std::invalid_argument("make_route: segments must be >= 2");
  const auto nodes = static_cast<std::size_t>(segments - 1);
  SheathRoute r;
  r.wrap_rad.assign(nodes, straight_rad / static_cast<double>(nodes));
  for (const Bend& b : bends) {
    if (!(b.width > 0.0) || !(b.angle_rad >= 0.0))
      throw std::invalid_argument("make_route: a bend needs width > 0 and angle >= 0");
    std::vector<double> w(nodes);
    double sum = 0.0;
    for (std::size_t i = 0; i < nodes; ++i) {
      const double s = static_cast<double>(i + 1) / segments;
      const double z = (s - b.centre) / b.width;
      w[i] = std::exp(-0.5 * z * z);
      sum += w[i];
    }
    for (std::size_t i = 0; i < nodes; ++i)
      r.wrap_rad[i] += b.angle_rad * w[i] / sum;
  }
  return r;
}

WorldParams random_world(std::uint64_t seed) {
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ULL + 0x5EA7);
  const auto uniform = [&](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  WorldParams w;
  w.seed = seed;
  TendonParams t;
  t.segments = 24;
  t.length_m = uniform(1.2, 1.8);
  t.ea_n = uniform(6000.0, 12000.0);
  t.pretension_n = uniform(18.0, 22.0);
  const double mu = uniform(0.10, 0.20);
  w.tendon1 = t;
  w.tendon2 = t;
  w.tendon1.mu = mu * uniform(0.9, 1.1);
  w.tendon2.mu = mu * uniform(0.9, 1.1);
  w.tendon1.base_normal_n = uniform(0.0, 0.05);
  w.tendon2.base_normal_n = uniform(0.0, 0.05);
  w.tendon1.drag_n_s_per_m = uniform(0.0, 0.5);
  w.tendon2.drag_n_s_per_m = uniform(0.0, 0.5);
  // Two sheaths bent differently: one takes 1.6-2.6 rad in two or three
  // bends, the other 45-80 % of that with bends of its own; which is the
  // more bent is drawn too.
  const auto bends = [&](double total) {
    const int count = uniform(0.0, 1.0) < 0.5 ? 2 : 3;
    std::vector<Bend> out;
    for (int i = 0; i < count; ++i)
      out.push_back({uniform(0.15, 0.9), uniform(0.03, 0.15), total / count * uniform(0.6, 1.4)});
    return out;
  };
  const double wrap_a = uniform(1.6, 2.6);
  const double wrap_b = wrap_a * uniform(0.45, 0.8);
  const double straight_a = uniform(0.1, 0.4), straight_b = uniform(0.1, 0.4);
  const bool swap = uniform(0.0, 1.0) < 0.5;
  w.route1 = make_route(t.segments, bends(swap ? wrap_b : wrap_a), swap ? straight_b : straight_a);
  w.route2 = make_route(t.segments, bends(swap ? wrap_a : wrap_b), swap ? straight_a : straight_b);
  TipParams& tip = w.tip;
  tip.inertia_kg_m2 = uniform(5e-6, 2e-5);
  tip.damping_n_m_s = uniform(1e-3, 4e-3);
  tip.tissue_surface_rad = uniform(0.3, 0.6);
  tip.tissue_stiffness = uniform(0.8, 2.0);
  tip.tissue_stiffening = uniform(0.0, 6.0);
  tip.tissue_damping = uniform(0.005, 0.02);
  tip.grasp_surface_rad = uniform(-0.9, -0.55);
  tip.grasp_stiffness = uniform(1.0, 2.5);
  tip.grasp_damping = uniform(0.005, 0.02);
  tip.external_peak_n_m = uniform(0.05, 0.12);
  w.substeps = stable_substeps(w);
  return w;
}

void validate(const WorldParams& p) {
  validate(p.tendon1);
  validate(p.tendon2);
  const auto segments1 = static_cast<std::size_t>(p.tendon1.segments);
  const auto segments2 = static_cast<std::size_t>(p.tendon2.segments);
  require(p.route1.wrap_rad.size() + 1 == segments1, "route1",
          "needs one wrap per inner node of tendon1");
  require(p.route2.wrap_rad.size() + 1 == segments2, "route2",
          "needs one wrap per inner node of tendon2");
  const TipParams& t = p.tip;
  require(finite_positive(t.radius_m), "tip.radius_m", "must be > 0");
  require(finite_positive(t.inertia_kg_m2), "tip.inertia_kg_m2", "must be > 0");
  require(t.damping_n_m_s >= 0.0, "tip.damping_n_m_s", "must be >= 0");
  require(t.tissue_stiffness >= 0.0 && t.tissue_stiffening >= 0.0 && t.tissue_damping >= 0.0,
          "tip.tissue_*", "must be >= 0");
  require(t.grasp_stiffness >= 0.0 && t.grasp_damping >= 0.0, "tip.grasp_*", "must be >= 0");
  require(t.grasp_surface_rad < t.tissue_surface_rad, "tip.grasp_surface_rad",
          "must be below tip.tissue_surface_rad");
  require(p.substeps >= 1 && p.substeps <= 10000, "substeps", "must be in [1, 10000]");
  require(p.reroute.ramp_s > 0.0, "reroute.ramp_s", "must be > 0");
  require(p.reroute.scale1 > 0.0 && p.reroute.scale2 > 0.0, "reroute.scale*", "must be > 0");
}

World::World(const WorldParams& params)
    : p_((validate(params), params)),
      t1_(params.tendon1, params.route1.wrap_rad),
      t2_(params.tendon2, params.route2.wrap_rad) {}

double World::tissue(double x, double xd) const {
  const TipParams& t = p_.tip;
  const double d = x - t.tissue_surface_rad;
  if (d <= 0.0) return 0.0;
  return std::max(0.0,
                  t.tissue_stiffness * d + t.tissue_stiffening * d * d * d + t.tissue_damping * xd);
}

double World::grasp(double x, double xd) const {
  const TipParams& t = p_.tip;
  const double d = t.grasp_surface_rad - x;
  if (d <= 0.0) return 0.0;
  return std::max(0.0, t.grasp_stiffness * d - t.grasp_damping * xd);
}

void World::apply_route(double t) {
  const Reroute& r = p_.reroute;
  if (!std::isfinite(r.at_s)) return;
  const double s = smoothstep((t - r.at_s) / r.ramp_s);
  t1_.set_wrap_scale(1.0 + (r.scale1 - 1.0) * s);
  t2_.set_wrap_scale(1.0 + (r.scale2 - 1.0) * s);
}

void World::step(double dt, double x_in, double xd_in, double xdd_in, double external_torque) {
  const double r = p_.tip.radius_m;
  // The inner nodes move with the ends where they were at the step's start;
  // then the tip moves with the tensions they leave (semi-implicit Euler).
  t1_.set_ends(r * x_in_, r * xd_in_, r * x_out_, r * xd_out_);
  t2_.set_ends(-r * x_in_, -r * xd_in_, -r * x_out_, -r * xd_out_);
  t1_.step(dt);
  t2_.step(dt);
  external_ = external_torque;
  if (!clamped_) {
    const double torque = r * (t1_.distal_tension() - t2_.distal_tension()) -
                          tissue(x_out_, xd_out_) + grasp(x_out_, xd_out_) + external_torque -
                          p_.tip.damping_n_m_s * xd_out_;
    xd_out_ += dt * torque / p_.tip.inertia_kg_m2;
    x_out_ += dt * xd_out_;
  }
  x_in_ = x_in;
  xd_in_ = xd_in;
  xdd_in_ = xdd_in;
  t1_.set_ends(r * x_in_, r * xd_in_, r * x_out_, r * xd_out_);
  t2_.set_ends(-r * x_in_, -r * xd_in_, -r * x_out_, -r * xd_out_);
}

TipState World::state() const {
  TipState s;
  s.x_in = x_in_;
  s.xd_in = xd_in_;
  s.xdd_in = xdd_in_;
  s.x_out = x_out_;
  s.xd_out = xd_out_;
  s.T1 = t1_.proximal_tension();
  s.T2 = t1_.distal_tension();
  s.T3 = t2_.proximal_tension();
  s.T4 = t2_.distal_tension();
  s.tissue_torque = tissue(x_out_, xd_out_);
  s.grasp_torque = grasp(x_out_, xd_out_);
  s.external_torque = external_;
  return s;
}

}  // namespace tsmh::physics_world
