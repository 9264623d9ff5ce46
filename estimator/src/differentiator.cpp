#include "estimator/differentiator.hpp"

#include <cmath>

namespace tsmh::estimator {
namespace {

using Mat3 = std::array<std::array<double, 3>, 3>;

// Covariance after the prediction over dt for the white-jerk model:
// P <- F P F^T + Q, F = [[1 dt dt^2/2] [0 1 dt] [0 0 1]], written out for the
// upper triangle (P is symmetric): a third of the work of the matrix products.
void predict_covariance(Mat3& p, double dt, double q) noexcept {
  const double h = 0.5 * dt * dt;
  // Rows of F P.
  const double r00 = p[0][0] + dt * p[1][0] + h * p[2][0];
  const double r01 = p[0][1] + dt * p[1][1] + h * p[2][1];
  const double r02 = p[0][2] + dt * p[1][2] + h * p[2][2];
  const double r11 = p[1][1] + dt * p[2][1];
  const double r12 = p[1][2] + dt * p[2][2];
  const double d2 = dt * dt, d3 = d2 * dt, d4 = d3 * dt, d5 = d4 * dt;
  const double p00 = r00 + dt * r01 + h * r02 + q * d5 / 20.0;
  const double p01 = r01 + dt * r02 + q * d4 / 8.0;
  const double p02 = r02 + q * d3 / 6.0;
  const double p11 = r11 + dt * r12 + q * d3 / 3.0;
  const double p12 = r12 + q * d2 / 2.0;
  const double p22 = p[2][2] + q * dt;
  p = {{{p00, p01, p02}, {p01, p11, p12}, {p02, p12, p22}}};
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
    // Steady-state acceleration uncertainty of this filter at 1 kHz. Encoder
    // quantisation makes the estimate oscillate up to ~1.6x this at constant
    // velocity, but never beyond 0.75x of it for a whole dwell time
    // (docs/friction-model.md): a low threshold plus the dwell switches
    // sooner than a high threshold alone.
    std::array<double, 3> s{};
    Mat3 p{};
    p[0][0] = r_;
    p[1][1] = 1e2;
    p[2][2] = 1e4;
    for (int i = 0; i < 5000; ++i) {
      predict_covariance(p, 1e-3, cfg_.jerk_psd);
      correct(s, p, 0.0, r_);
    }
    threshold_ = 0.75 * std::sqrt(p[2][2]);
  }
  reset();
}

void Differentiator::reset() noexcept {
  started_ = false;
  pending_sign_ = 0;
  pending_time_ = 0.0;
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
  pending_sign_ = 0;
  pending_time_ = 0.0;
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

  // sgn(xdd): unknown (0) from the moment the estimate crosses zero; +-1 once
  // |xdd| has stayed beyond the threshold with that sign for the dwell time.
  int sign = out_.acc_sign;
  if (sign * s_[2] < 0.0) sign = 0;
  const int want = s_[2] > threshold_ ? 1 : (s_[2] < -threshold_ ? -1 : 0);
  if (want != 0 && want != sign) {
    pending_time_ = want == pending_sign_ ? pending_time_ + dt : dt;
    pending_sign_ = want;
    if (pending_time_ >= cfg_.acc_sign_dwell - 1e-9) {
      sign = want;
      pending_sign_ = 0;
    }
  } else {
    pending_sign_ = 0;
  }
  out_ = {s_[0], s_[1], s_[2], sign, true};
  return out_;
}

}  // namespace tsmh::estimator
