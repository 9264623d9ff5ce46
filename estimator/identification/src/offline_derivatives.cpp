#include "estimator/offline_derivatives.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace tsmh::estimator {
namespace {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<std::array<double, 3>, 3>;

Mat3 transition(double dt) {
  return {{{1.0, dt, 0.5 * dt * dt}, {0.0, 1.0, dt}, {0.0, 0.0, 1.0}}};
}

// Process noise of white jerk of density q over dt.
Mat3 process_noise(double dt, double q) {
  const double d2 = dt * dt, d3 = d2 * dt, d4 = d3 * dt, d5 = d4 * dt;
  return {{{q * d5 / 20.0, q * d4 / 8.0, q * d3 / 6.0},
           {q * d4 / 8.0, q * d3 / 3.0, q * d2 / 2.0},
           {q * d3 / 6.0, q * d2 / 2.0, q * dt}}};
}

Mat3 mul(const Mat3& a, const Mat3& b) {
  Mat3 c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = 0; k < 3; ++k)
        c[i][j] += a[i][k] * b[k][j];
  return c;
}

Mat3 transpose(const Mat3& a) {
  Mat3 c{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      c[i][j] = a[j][i];
  return c;
}

Vec3 mul(const Mat3& a, const Vec3& v) {
  Vec3 r{};
  for (int i = 0; i < 3; ++i)
    for (int k = 0; k < 3; ++k)
      r[i] += a[i][k] * v[k];
  return r;
}

// Inverse of a symmetric positive definite 3x3 matrix (cofactors).
Mat3 inverse(const Mat3& m) {
  Mat3 c{};
  c[0][0] = m[1][1] * m[2][2] - m[1][2] * m[2][1];
  c[0][1] = m[0][2] * m[2][1] - m[0][1] * m[2][2];
  c[0][2] = m[0][1] * m[1][2] - m[0][2] * m[1][1];
  c[1][0] = m[1][2] * m[2][0] - m[1][0] * m[2][2];
  c[1][1] = m[0][0] * m[2][2] - m[0][2] * m[2][0];
  c[1][2] = m[0][2] * m[1][0] - m[0][0] * m[1][2];
  c[2][0] = m[1][0] * m[2][1] - m[1][1] * m[2][0];
  c[2][1] = m[0][1] * m[2][0] - m[0][0] * m[2][1];
  c[2][2] = m[0][0] * m[1][1] - m[0][1] * m[1][0];
  const double det = m[0][0] * c[0][0] + m[0][1] * c[1][0] + m[0][2] * c[2][0];
  for (auto& row : c)
    for (auto& v : row)
      v /= det;
  return c;
}

}  // namespace

SmoothedDerivatives smooth_derivatives(std::span<const double> t, std::span<const double> x,
                                       const OfflineDerivativeConfig& cfg) {
  const std::size_t n = t.size();
  if (x.size() != n) throw std::invalid_argument("smooth_derivatives: t and x differ in length");
  if (n < 3) throw std::invalid_argument("smooth_derivatives: needs at least 3 samples");
  double r = cfg.quantum * cfg.quantum / 12.0 + cfg.position_noise * cfg.position_noise;
  if (!(r > 0.0)) r = 1e-12;
  const double q = cfg.jerk_psd;

  // Forward Kalman filter; keep the predicted and filtered moments for the
  // backward pass (40 s at 1 kHz: about 8 MB, freed on return).
  std::vector<Vec3> s_pred(n), s_filt(n);
  std::vector<Mat3> p_pred(n), p_filt(n);
  Vec3 s{x[0], 0.0, 0.0};
  // Diffuse start: velocity and acceleration unknown.
  Mat3 p{{{r, 0.0, 0.0}, {0.0, 1e2, 0.0}, {0.0, 0.0, 1e4}}};
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) {
      const double dt = t[i] - t[i - 1];
      const Mat3 f = transition(dt);
      s = mul(f, s);
      p = mul(mul(f, p), transpose(f));
      const Mat3 qn = process_noise(dt, q);
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          p[a][b] += qn[a][b];
    }
    s_pred[i] = s;
    p_pred[i] = p;
    const double inv = 1.0 / (p[0][0] + r);
    const double k[3] = {p[0][0] * inv, p[1][0] * inv, p[2][0] * inv};
    const double innovation = x[i] - s[0];
    for (int a = 0; a < 3; ++a)
      s[a] += k[a] * innovation;
    const double row0[3] = {p[0][0], p[0][1], p[0][2]};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        p[a][b] -= k[a] * row0[b];
    s_filt[i] = s;
    p_filt[i] = p;
  }

  // Backward Rauch-Tung-Striebel pass.
  SmoothedDerivatives out;
  out.x.resize(n);
  out.xd.resize(n);
  out.xdd.resize(n);
  out.xdd_std.resize(n);
  Vec3 s_next = s_filt[n - 1];
  Mat3 p_next = p_filt[n - 1];
  const auto store = [&](std::size_t i, const Vec3& v, const Mat3& c) {
    out.x[i] = v[0];
    out.xd[i] = v[1];
    out.xdd[i] = v[2];
    out.xdd_std[i] = std::sqrt(std::max(c[2][2], 0.0));
  };
  store(n - 1, s_next, p_next);
  for (std::size_t i = n - 1; i-- > 0;) {
    const Mat3 f = transition(t[i + 1] - t[i]);
    const Mat3 gain = mul(mul(p_filt[i], transpose(f)), inverse(p_pred[i + 1]));
    Vec3 d{};
    for (int a = 0; a < 3; ++a)
      d[a] = s_next[a] - s_pred[i + 1][a];
    Vec3 sm = s_filt[i];
    const Vec3 corr = mul(gain, d);
    for (int a = 0; a < 3; ++a)
      sm[a] += corr[a];
    Mat3 dp{};
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        dp[a][b] = p_next[a][b] - p_pred[i + 1][a][b];
    const Mat3 add = mul(mul(gain, dp), transpose(gain));
    Mat3 pm = p_filt[i];
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        pm[a][b] += add[a][b];
    store(i, sm, pm);
    s_next = sm;
    p_next = pm;
  }
  return out;
}

std::vector<Motion> offline_motion(const Recording& rec, const OfflineDerivativeConfig& cfg) {
  const auto sm = smooth_derivatives(rec.t, rec.x_in, cfg);
  const bool has_load = rec.has_tau_in() && std::isfinite(rec.radius_m) && rec.radius_m > 0.0;
  const bool has_tensions = rec.T1.size() == rec.size() && rec.T3.size() == rec.size();
  std::vector<Motion> motion(rec.size());
  for (std::size_t i = 0; i < rec.size(); ++i) {
    Motion& m = motion[i];
    m.t = rec.t[i];
    m.x = rec.x_in[i];
    m.xd = sm.xd[i];
    m.xdd = sm.xdd[i];
    if (cfg.expected_sign) {
      const double sd = std::max(sm.xdd_std[i], 1e-12);
      m.acc_sign = std::erf(sm.xdd[i] / (std::numbers::sqrt2 * sd));
    } else {
      m.acc_sign =
          std::fabs(sm.xdd[i]) > cfg.acc_sign_sigmas * sm.xdd_std[i] ? sign_of(sm.xdd[i]) : 0;
    }
    m.load = has_load ? std::fabs(rec.tau_in[i]) / rec.radius_m : 0.0;
    if (has_load) m.drive = rec.tau_in[i] / rec.radius_m;
    if (has_tensions) m.tension = 0.5 * (rec.T1[i] + rec.T3[i]);
    m.x_out = rec.x_out_at(i);
  }
  return motion;
}

}  // namespace tsmh::estimator
