#include "physics_world/tendon.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tsmh::physics_world {

namespace {

void require(bool ok, const char* field, const char* what) {
  if (!ok) throw std::invalid_argument(std::string("tendon.") + field + ": " + what);
}

}  // namespace

void validate(const TendonParams& p) {
  require(p.segments >= 2 && p.segments <= 1000, "segments", "must be in [2, 1000]");
  require(p.length_m > 0.0 && std::isfinite(p.length_m), "length_m", "must be > 0");
  require(p.ea_n > 0.0 && std::isfinite(p.ea_n), "ea_n", "must be > 0");
  require(p.node_mass_kg > 0.0 && std::isfinite(p.node_mass_kg), "node_mass_kg", "must be > 0");
  require(p.damping_ratio >= 0.0 && p.damping_ratio < 1.0, "damping_ratio", "must be in [0, 1)");
  require(p.mu >= 0.0 && std::isfinite(p.mu), "mu", "must be >= 0");
  require(p.base_normal_n >= 0.0 && std::isfinite(p.base_normal_n), "base_normal_n",
          "must be >= 0");
  require(p.drag_n_s_per_m >= 0.0 && std::isfinite(p.drag_n_s_per_m), "drag_n_s_per_m",
          "must be >= 0");
  require(p.pretension_n >= 0.0 && std::isfinite(p.pretension_n), "pretension_n", "must be >= 0");
}

Tendon::Tendon(const TendonParams& params, std::vector<double> wrap_rad)
    : p_(params), segments_(params.segments), wrap_(std::move(wrap_rad)) {
  validate(p_);
  if (wrap_.size() != static_cast<std::size_t>(segments_ - 1))
    throw std::invalid_argument(
        "tendon: wrap must have segments - 1 = " + std::to_string(segments_ - 1) + " values, got " +
        std::to_string(wrap_.size()));
  for (double w : wrap_)
    require(w >= 0.0 && std::isfinite(w), "wrap", "every node's wrap must be >= 0 and finite");
  k_ = p_.ea_n * segments_ / p_.length_m;
  inv_m_ = 1.0 / p_.node_mass_kg;
  // The chain's highest mode: omega^2 = 4 k / m; relative-velocity damping c
  // adds 4 c / m = 2 zeta omega there.
  c_ = p_.damping_ratio * std::sqrt(4.0 * k_ / p_.node_mass_kg) * p_.node_mass_kg / 2.0;
  u_.assign(static_cast<std::size_t>(segments_) + 1, 0.0);
  v_.assign(u_.size(), 0.0);
  t_.assign(u_.size(), p_.pretension_n);
}

void Tendon::set_ends(double u_proximal, double v_proximal, double u_distal, double v_distal) {
  u_.front() = u_proximal;
  v_.front() = v_proximal;
  u_.back() = u_distal;
  v_.back() = v_distal;
}

double Tendon::tension(int segment) const {
  const auto i = static_cast<std::size_t>(segment);
  const double stretch = u_[i - 1] - u_[i];
  const double rate = v_[i - 1] - v_[i];
  return std::max(0.0, p_.pretension_n + k_ * stretch + c_ * rate);
}

double Tendon::total_wrap() const {
  double w = 0.0;
  for (double x : wrap_)
    w += x;
  return w * wrap_scale_;
}

double Tendon::stored_energy() const {
  double e = 0.0;
  for (int s = 1; s <= segments_; ++s) {
    const auto i = static_cast<std::size_t>(s);
    const double stretch = u_[i - 1] - u_[i];
    // Elastic energy beyond the pretensioned rest state, while taut.
    const double slack_at = -p_.pretension_n / k_;
    const double x = std::max(stretch, slack_at);
    e += p_.pretension_n * x + 0.5 * k_ * x * x;
  }
  for (std::size_t i = 1; i + 1 < u_.size(); ++i)
    e += 0.5 * p_.node_mass_kg * v_[i] * v_[i];
  return e;
}

void Tendon::step(double dt) {
  const auto n = static_cast<std::size_t>(segments_);
  for (std::size_t i = 1; i <= n; ++i)
    t_[i] = tension(static_cast<int>(i));
  int stuck = 0;
  const double impulse_per_n = dt * inv_m_;
  for (std::size_t i = 1; i < n; ++i) {
    const double force = t_[i] - t_[i + 1] - p_.drag_n_s_per_m * v_[i];
    const double v_free = v_[i] + impulse_per_n * force;
    // The sheath presses on the node with the local tension times its bend
    // (the mean of the two segments meeting there) plus what bending
    // stiffness adds; Coulomb friction up to mu times that.
    const double normal = wrap_[i - 1] * wrap_scale_ * 0.5 * (t_[i] + t_[i + 1]) + p_.base_normal_n;
    const double limit = impulse_per_n * p_.mu * normal;
    double v_new;
    if (std::fabs(v_free) <= limit) {
      v_new = 0.0;  // stuck: static friction holds the node
      ++stuck;
    } else {
      v_new = v_free - std::copysign(limit, v_free);
    }
    // Friction's and drag's work on the node this step (never positive).
    const double friction_force = (v_new - v_free) / impulse_per_n;
    dissipated_ += -(friction_force * v_new - p_.drag_n_s_per_m * v_[i] * v_new) * dt;
    v_[i] = v_new;
    u_[i] += dt * v_new;
  }
  stuck_ = stuck;
}

}  // namespace tsmh::physics_world
