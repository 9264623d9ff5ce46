#include "virtual_tissue_slave/tendon_chain.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tsmh::virtual_tissue_slave {
namespace {

void require(bool ok, const std::string& field, const std::string& why) {
  if (!ok) throw std::invalid_argument("tendon parameter '" + field + "' " + why);
}

// Tolerances of the active-set checks: a node may exceed its friction cone by
// this much tension, or move against its slip direction by this much, before
// its regime flips. Far below sensor resolution, far above round-off.
constexpr double kTensionTol = 1e-9;
constexpr double kPositionTol = 1e-13;
constexpr int kMaxActiveSetIterations = 64;

}  // namespace

TendonChain::TendonChain(const TendonParams& params) : params_(params) {
  require(std::isfinite(params.length_m) && params.length_m > 0, "length_m", "must be > 0");
  require(std::isfinite(params.stiffness_ea_n) && params.stiffness_ea_n > 0, "stiffness_ea_n",
          "must be > 0");
  require(std::isfinite(params.pretension_n) && params.pretension_n >= 0, "pretension_n",
          "must be >= 0");
  require(std::isfinite(params.mu) && params.mu >= 0, "mu", "must be >= 0");
  require(params.segments >= 2 && params.segments <= 1000, "segments", "must be in [2, 1000]");
  segments_ = params.segments;
  k_ = params.stiffness_ea_n / (params.length_m / segments_);
  const auto n = static_cast<std::size_t>(segments_ + 1);
  s_.assign(n, 0.0);
  s_prev_.assign(n, 0.0);
  tension_.assign(n, params.pretension_n);
  tension_[0] = 0.0;  // no segment 0
  regime_.assign(n, 0);
  taut_.assign(n, params.pretension_n > 0 ? 1 : 0);
  lower_.assign(n, 0.0);
  diag_.assign(n, 0.0);
  upper_.assign(n, 0.0);
  rhs_.assign(n, 0.0);
  set_wrap(params.wrap_rad);
}

void TendonChain::set_wrap(double wrap_rad) {
  require(std::isfinite(wrap_rad) && wrap_rad >= 0, "wrap_rad", "must be >= 0");
  wrap_rad_ = wrap_rad;
  half_mu_dtheta_ = 0.5 * params_.mu * wrap_rad / (segments_ - 1);
  // a >= 1 would mean one node can hold any tension ratio: the discretisation
  // is too coarse for this much wrap.
  require(half_mu_dtheta_ < 0.5, "wrap_rad",
          "too large for the number of segments (mu * wrap / (segments - 1) must be < 1)");
}

double TendonChain::raw_tension(int j) const {
  const auto u = static_cast<std::size_t>(j);
  return params_.pretension_n + k_ * (s_[u - 1] - s_[u]);
}

double TendonChain::node_bound(int i) const {
  const auto u = static_cast<std::size_t>(i);
  if (friction_.capstan) return half_mu_dtheta_ * (tension_[u] + tension_[u + 1]);
  return half_mu_dtheta_ * 2.0 * params_.pretension_n;
}

void TendonChain::refresh_tensions() {
  for (int j = 1; j <= segments_; ++j) {
    const auto u = static_cast<std::size_t>(j);
    tension_[u] = taut_[u] ? std::max(0.0, raw_tension(j)) : 0.0;
  }
}

double TendonChain::elastic_energy() const {
  const double p = params_.pretension_n;
  double e_total = 0.0;
  for (int j = 1; j <= segments_; ++j) {
    const auto u = static_cast<std::size_t>(j);
    const double e = s_[u - 1] - s_[u];
    e_total += (p + k_ * e >= 0.0) ? p * e + 0.5 * k_ * e * e : -p * p / (2.0 * k_);
  }
  return e_total;
}

// Builds the linear system for the current regimes (stick: s_i = s_prev_i;
// slip sigma: force balance with friction at its bound) and solves it with the
// Thomas algorithm. Then checks every node and segment against its regime and
// flips the violators. The regimes of the previous step are the starting
// guess, so a step usually settles in one or two iterations.
bool TendonChain::solve_active_set(double dt, int& iterations) {
  const double a = half_mu_dtheta_;
  const double p = params_.pretension_n;
  const double c = friction_.viscous_n_s_per_m / dt;
  const double cap = friction_.capstan ? 1.0 : 0.0;
  const int m = segments_ - 1;  // unknowns: nodes 1..N-1
  const double s0 = s_[0];
  const double sn = s_[static_cast<std::size_t>(segments_)];

  for (iterations = 1; iterations <= kMaxActiveSetIterations; ++iterations) {
    for (int i = 1; i <= m; ++i) {
      const auto u = static_cast<std::size_t>(i);
      const double ti = taut_[u];
      const double tn = taut_[u + 1];
      const int sigma = regime_[u];
      double lo = 0.0, di = 1.0, up = 0.0, r = s_prev_[u];
      if (sigma != 0) {
        const double alpha = 1.0 - sigma * a * cap;
        const double beta = 1.0 + sigma * a * cap;
        lo = alpha * ti * k_;
        up = beta * tn * k_;
        di = -lo - up - c;
        r = -alpha * ti * p + beta * tn * p - c * s_prev_[u] + sigma * 2.0 * a * p * (1.0 - cap);
        if (di == 0.0) {  // both neighbours slack and no drag: nothing can move it
          lo = up = 0.0;
          di = 1.0;
          r = s_prev_[u];
          regime_[u] = 0;
        }
      }
      if (i == 1) {
        r -= lo * s0;
        lo = 0.0;
      }
      if (i == m) {
        r -= up * sn;
        up = 0.0;
      }
      lower_[u] = lo;
      diag_[u] = di;
      upper_[u] = up;
      rhs_[u] = r;
    }
    // Thomas algorithm (the matrix is diagonally dominant: no pivoting needed).
    for (int i = 2; i <= m; ++i) {
      const auto u = static_cast<std::size_t>(i);
      const double w = lower_[u] / diag_[u - 1];
      diag_[u] -= w * upper_[u - 1];
      rhs_[u] -= w * rhs_[u - 1];
    }
    s_[static_cast<std::size_t>(m)] =
        rhs_[static_cast<std::size_t>(m)] / diag_[static_cast<std::size_t>(m)];
    for (int i = m - 1; i >= 1; --i) {
      const auto u = static_cast<std::size_t>(i);
      s_[u] = (rhs_[u] - upper_[u] * s_[u + 1]) / diag_[u];
    }

    bool changed = false;
    for (int j = 1; j <= segments_; ++j) {
      const auto u = static_cast<std::size_t>(j);
      const double raw = raw_tension(j);
      if (taut_[u] && raw < -kTensionTol) {
        taut_[u] = 0;
        changed = true;
      } else if (!taut_[u] && raw > kTensionTol) {
        taut_[u] = 1;
        changed = true;
      }
    }
    refresh_tensions();
    for (int i = 1; i <= m; ++i) {
      const auto u = static_cast<std::size_t>(i);
      if (regime_[u] == 0) {
        const double r = tension_[u] - tension_[u + 1];
        if (std::abs(r) > node_bound(i) + kTensionTol) {
          regime_[u] = r > 0 ? 1 : -1;
          changed = true;
        }
      } else if (regime_[u] * (s_[u] - s_prev_[u]) < -kPositionTol) {
        regime_[u] = 0;
        changed = true;
      }
    }
    if (!changed) return true;
  }
  return false;
}

// Robust but slow: node by node, stick if the friction cone holds the node at
// its old position, else slide to where friction sits exactly at its bound.
// The slip equation is monotone in the node position, piecewise linear
// (segments may go slack), so a few Newton steps on it are exact.
void TendonChain::solve_projected_gauss_seidel(double dt) {
  const double c = friction_.viscous_n_s_per_m / dt;
  const int m = segments_ - 1;
  for (int j = 1; j <= segments_; ++j)
    taut_[static_cast<std::size_t>(j)] = 1;
  for (int sweep = 0; sweep < 20000; ++sweep) {
    double max_change = 0.0;
    for (int step = 0; step < m; ++step) {
      const int i = (sweep % 2 == 0) ? 1 + step : m - step;
      const auto u = static_cast<std::size_t>(i);
      const double before = s_[u];
      auto residual = [&](double d, double sigma) {
        s_[u] = d;
        const double ti = std::max(0.0, raw_tension(i));
        const double tn = std::max(0.0, raw_tension(i + 1));
        const double bound = friction_.capstan ? half_mu_dtheta_ * (ti + tn)
                                               : half_mu_dtheta_ * 2.0 * params_.pretension_n;
        return ti - tn - sigma * bound - c * (d - s_prev_[u]);
      };
      const double r_stick = residual(s_prev_[u], 0.0);
      s_[u] = s_prev_[u];
      const double ti = std::max(0.0, raw_tension(i));
      const double tn = std::max(0.0, raw_tension(i + 1));
      const double bound = friction_.capstan ? half_mu_dtheta_ * (ti + tn)
                                             : half_mu_dtheta_ * 2.0 * params_.pretension_n;
      if (std::abs(r_stick) > bound) {
        const double sigma = r_stick > 0 ? 1.0 : -1.0;
        // Bracket the root on the slip side, then bisect: g is monotone decreasing.
        double lo = s_prev_[u], hi = s_prev_[u];
        double span = std::abs(r_stick) / k_ + 1e-12;
        for (int grow = 0; grow < 200; ++grow) {
          const double probe = s_prev_[u] + sigma * span;
          if (sigma * residual(probe, sigma) <= 0.0) {
            (sigma > 0 ? hi : lo) = probe;
            break;
          }
          (sigma > 0 ? lo : hi) = probe;
          span *= 2.0;
        }
        for (int bis = 0; bis < 80; ++bis) {
          const double mid = 0.5 * (lo + hi);
          if (residual(mid, sigma) > 0.0)
            lo = mid;
          else
            hi = mid;
        }
        s_[u] = 0.5 * (lo + hi);
      }
      max_change = std::max(max_change, std::abs(s_[u] - before));
    }
    if (max_change < kPositionTol) break;
  }
  for (int j = 1; j <= segments_; ++j) {
    const auto u = static_cast<std::size_t>(j);
    taut_[u] = raw_tension(j) > 0.0 ? 1 : 0;
  }
  refresh_tensions();
  for (int i = 1; i <= m; ++i) {
    const auto u = static_cast<std::size_t>(i);
    const double ds = s_[u] - s_prev_[u];
    regime_[u] = ds > kPositionTol ? 1 : (ds < -kPositionTol ? -1 : 0);
  }
}

ChainSolveInfo TendonChain::solve(double s_proximal, double s_distal, double dt) {
  ChainSolveInfo info;
  const auto last = static_cast<std::size_t>(segments_);
  std::copy(s_.begin(), s_.end(), s_prev_.begin());
  s_[0] = s_proximal;
  s_[last] = s_distal;
  if (!solve_active_set(dt, info.iterations)) {
    info.used_fallback = true;
    std::copy(s_prev_.begin() + 1, s_prev_.end() - 1, s_.begin() + 1);
    solve_projected_gauss_seidel(dt);
  }
  // Work done on the interior nodes by the segments = energy dissipated there
  // by friction and drag (the nodes are massless and store nothing).
  for (int i = 1; i < segments_; ++i) {
    const auto u = static_cast<std::size_t>(i);
    info.dissipated_j += (tension_[u] - tension_[u + 1]) * (s_[u] - s_prev_[u]);
  }
  return info;
}

}  // namespace tsmh::virtual_tissue_slave
