#include "estimator/synthetic.hpp"

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

namespace tsmh::estimator {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// A sum of sines and its first two derivatives at t.
struct MultiSine {
  std::vector<double> amp, omega, phase;

  void eval(double t, double& x, double& xd, double& xdd) const {
    x = xd = xdd = 0.0;
    for (std::size_t k = 0; k < amp.size(); ++k) {
      const double a = omega[k] * t + phase[k];
      const double s = std::sin(a), c = std::cos(a);
      x += amp[k] * s;
      xd += amp[k] * omega[k] * c;
      xdd -= amp[k] * omega[k] * omega[k] * s;
    }
  }
};

MultiSine random_multisine(int components, double f_low, double f_high, double weight_exponent,
                           std::mt19937_64& rng) {
  std::uniform_real_distribution<double> phase(0.0, kTwoPi);
  MultiSine m;
  for (int k = 0; k < components; ++k) {
    const double r = components > 1 ? static_cast<double>(k) / (components - 1) : 0.0;
    const double f = f_low * std::pow(f_high / f_low, r);
    m.omega.push_back(kTwoPi * f);
    m.amp.push_back(std::pow(f_low / f, weight_exponent));
    m.phase.push_back(phase(rng));
  }
  return m;
}

// Scales the amplitudes so that the peak |x| over [0, duration] is `peak`.
void normalise_peak(MultiSine& m, double duration, double peak) {
  double largest = 0.0;
  for (double t = 0.0; t <= duration; t += 1e-3) {
    double x, xd, xdd;
    m.eval(t, x, xd, xdd);
    largest = std::max(largest, std::fabs(x));
  }
  if (largest <= 0.0) return;
  for (auto& a : m.amp)
    a *= peak / largest;
}

// Raised-cosine fade-in from rest over `fade` seconds before t = 0, and its
// derivatives: the joint starts at rest during a pre-roll that is not
// recorded, so the recording begins in ordinary motion, as a real one does.
void envelope(double t, double fade, double& e, double& ed, double& edd) {
  if (t >= 0.0) {
    e = 1.0;
    ed = edd = 0.0;
    return;
  }
  const double w = std::numbers::pi / fade;
  const double a = w * (t + fade);
  e = 0.5 * (1.0 - std::cos(a));
  ed = 0.5 * w * std::sin(a);
  edd = 0.5 * w * w * std::cos(a);
}

}  // namespace

SyntheticData make_synthetic(const FrictionModel& truth, const SyntheticConfig& c) {
  if (!(c.duration_s > 0.0) || !(c.rate_hz > 0.0) || !(c.radius_m > 0.0) || c.components < 1 ||
      !(c.f_low_hz > 0.0) || !(c.f_high_hz >= c.f_low_hz) || c.substeps < 1 ||
      c.torque_noise < 0.0 || c.quantum < 0.0) {
    throw std::invalid_argument("make_synthetic: unusable configuration");
  }
  std::mt19937_64 rng(c.seed);
  MultiSine motion = random_multisine(c.components, c.f_low_hz, c.f_high_hz, 0.5, rng);
  normalise_peak(motion, c.duration_s, c.amplitude_rad);
  // The load varies more slowly than the motion and independently of it, so
  // that load-dependent friction can be told apart from position or speed.
  MultiSine load = random_multisine(3, 0.05, 0.23, 0.0, rng);
  normalise_peak(load, c.duration_s, 1.0);
  std::normal_distribution<double> noise(0.0, c.torque_noise);

  const auto n = static_cast<std::size_t>(std::floor(c.duration_s * c.rate_hz)) + 1;
  const double dt = 1.0 / c.rate_hz;
  const double fade = 1.0;  // s of pre-roll
  auto model = truth.clone();
  model->reset();

  SyntheticData out;
  Recording& rec = out.recording;
  rec.source = "synthetic(seed " + std::to_string(c.seed) + ")";
  rec.radius_m = c.radius_m;
  rec.t.resize(n);
  rec.x_in.resize(n);
  rec.tau_in.resize(n);
  rec.tau_out.resize(n);
  if (c.exact_derivatives) {
    rec.xd_in.resize(n);
    rec.xdd_in.resize(n);
  }
  out.true_friction.resize(n);

  const auto state_at = [&](double t, double f_prev) {
    double s, sd, sdd, e, ed, edd, l, ld, ldd;
    motion.eval(t, s, sd, sdd);
    envelope(t, fade, e, ed, edd);
    load.eval(t, l, ld, ldd);
    Motion m;
    m.t = t;
    m.x = e * s;
    m.xd = ed * s + e * sd;
    m.xdd = edd * s + 2.0 * ed * sd + e * sdd;
    m.acc_sign = sign_of(m.xdd);
    const double tau_out = c.load_offset + c.load_amplitude * e * l;
    m.load = std::fabs(tau_out + c.radius_m * f_prev) / c.radius_m;
    return std::pair{m, tau_out};
  };

  // Pre-roll: the true model runs through the fade-in from rest, unrecorded.
  double f = 0.0;
  const auto pre = static_cast<long>(std::ceil(fade * c.rate_hz));
  const double h = dt / c.substeps;
  for (long i = -pre; i < static_cast<long>(n); ++i) {
    if (i > -pre) {
      for (int k = 1; k <= c.substeps; ++k) {
        const double tk = static_cast<double>(i - 1) * dt + k * h;
        f = model->step(state_at(tk, f).first, h);
      }
    }
    if (i < 0) continue;
    const double t = static_cast<double>(i) * dt;
    const auto [m, tau_out] = state_at(t, f);
    const auto j = static_cast<std::size_t>(i);
    rec.t[j] = t;
    rec.x_in[j] = c.quantum > 0.0 ? std::round(m.x / c.quantum) * c.quantum : m.x;
    rec.tau_out[j] = tau_out + noise(rng);
    rec.tau_in[j] = tau_out + c.radius_m * f + noise(rng);
    if (c.exact_derivatives) {
      rec.xd_in[j] = m.xd;
      rec.xdd_in[j] = m.xdd;
    }
    out.true_friction[j] = f;
  }
  return out;
}

}  // namespace tsmh::estimator
