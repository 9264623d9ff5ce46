#include "estimator/differentiator.hpp"

#include <cmath>

namespace tsmh::estimator {
namespace {

using Mat3 = std::array<std::array<double, 3>, 3>;

// Covariance after the prediction over dt for the white-jerk model:
// P <- F P F^T + Q, F = [[1 dt dt^2/2] [0 1 dt] [0 0 1]].
void predict_covariance(Mat3& p, double dt, double q) noexcept {
  const double h = 0.5 * dt * dt;
  const double f[3][3] = {{1.0, dt, h}, {0.0, 1.0, dt}, {0.0, 0.0, 1.0}};
  Mat3 fp{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = i; k < 3; ++k)
        fp[i][j] += f[i][k] * p[k][j];
  Mat3 out{};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      for (int k = j; k < 3; ++k)
        out[i][j] += fp[i][k] * f[j][k];
  const double d2 = dt * dt, d3 = d2 * dt, d4 = d3 * dt, d5 = d4 * dt;
  const double qm[3][3] = {
      {d5 / 20.0, d4 / 8.0, d3 / 6.0}, {d4 / 8.0, d3 / 3.0, d2 / 2.0}, {d3 / 6.0, d2 / 2.0, dt}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      p[i][j] = out[i][j] + q * qm[i][j];
}

// Measurement update with the angle; returns the gain-weighted innovation.
void correct(std::array<double, 3>& s, Mat3& p, double z, double r) noexcept {
  const double inv = 1.0 / (p[0][0] + r);
  const double k[3] = {p[0][0] * inv, p[1][0] * inv, p[2][0] * inv};
  const double innovation = z - s[0];
  for (int i = 0; i < 3; ++i)
    s[i] += k[i] * innovation;
  const double row0[3] = {p[0][0], p[0][1], p[0][2]};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      p[i][j] -= k[i] * row0[j];
}

Derivatives invalidated(Derivatives last) noexcept {
  last.valid = false;
  return last;
}

}  // namespace

Differentiator::Differentiator(const DifferentiatorConfig& config)
    : cfg_(config),
      r_(config.quantum * config.quantum / 12.0 + config.position_noise * config.position_noise) {
  if (!(r_ > 0.0)) r_ = 1e-12;
  threshold_ = cfg_.acc_sign_threshold;
  if (threshold_ < 0.0) {
    // Steady-state acceleration uncertainty of this filter at 1 kHz.
    std::array<double, 3> s{};
    Mat3 p{};
    p[0][0] = r_;
    p[1][1] = 1e2;
    p[2][2] = 1e4;
    for (int i = 0; i < 5000; ++i) {
      predict_covariance(p, 1e-3, cfg_.jerk_psd);
      correct(s, p, 0.0, r_);
    }
    threshold_ = 1.5 * std::sqrt(p[2][2]);
  }
  reset();
}

void Differentiator::reset() noexcept {
  started_ = false;
  out_ = {};
}

void Differentiator::start(double t, double x) noexcept {
  started_ = true;
  t_ = t;
  s_ = {x, 0.0, 0.0};
  p_ = {};
  p_[0][0] = r_;
  // Prior spread of velocity and acceleration at start: generous for a hand
  // or a motor (rad/s, rad/s^2), so the first samples dominate.
  p_[1][1] = 10.0 * 10.0;
  p_[2][2] = 100.0 * 100.0;
  out_ = {x, 0.0, 0.0, 0, true};
}

Derivatives Differentiator::update(double t, double x) noexcept {
  if (!std::isfinite(t) || !std::isfinite(x)) return invalidated(out_);
  if (!started_) {
    start(t, x);
    return out_;
  }
  const double dt = t - t_;
  if (!(dt > 0.0)) return invalidated(out_);
  if (dt > cfg_.max_gap) {
    start(t, x);
    return out_;
  }
  t_ = t;
  // State prediction with F, then the covariance, then the correction.
  s_[0] += dt * s_[1] + 0.5 * dt * dt * s_[2];
  s_[1] += dt * s_[2];
  predict_covariance(p_, dt, cfg_.jerk_psd);
  correct(s_, p_, x, r_);

  int sign = out_.acc_sign;
  if (s_[2] > threshold_) sign = 1;
  if (s_[2] < -threshold_) sign = -1;
  out_ = {s_[0], s_[1], s_[2], sign, true};
  return out_;
}

}  // namespace tsmh::estimator
