#include "estimator/synthetic.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>

#include "realtime/enum_names.hpp"

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
// A quintic smoothstep from 0 at t = -fade to 1 at t = 0: its first and
// second derivatives vanish at both ends, so the faded motion's acceleration
// is continuous (a raised cosine left a step of about 3 rad/s^2 at t = 0).
void envelope(double t, double fade, double& e, double& ed, double& edd) {
  if (t >= 0.0) {
    e = 1.0;
    ed = edd = 0.0;
    return;
  }
  const double u = std::clamp((t + fade) / fade, 0.0, 1.0);
  e = u * u * u * (10.0 + u * (-15.0 + 6.0 * u));
  ed = 30.0 * u * u * (1.0 - u) * (1.0 - u) / fade;
  edd = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / (fade * fade);
}

// A velocity profile made of raised-cosine transitions between speed levels:
// continuous velocity and acceleration, exact closed forms for x, xd and xdd,
// and exact rest (xd = xdd = 0) during holds.
struct VelocitySegment {
  double t0, duration, v0, v1, x0;
};

class VelocityProfile {
 public:
  explicit VelocityProfile(double t_start) : t_(t_start) {}

  /// Appends a transition from the current speed to `v1` over `duration` s
  /// (a hold when v1 equals the current speed).
  void go(double v1, double duration) {
    segments_.push_back({t_, duration, v_, v1, x_});
    x_ += 0.5 * (v_ + v1) * duration;
    v_ = v1;
    t_ += duration;
  }
  double t() const { return t_; }
  double x() const { return x_; }
  double v() const { return v_; }

  void eval(double t, double& x, double& xd, double& xdd) const {
    auto it = std::upper_bound(segments_.begin(), segments_.end(), t,
                               [](double v, const VelocitySegment& s) { return v < s.t0; });
    if (it != segments_.begin()) --it;
    const VelocitySegment& s = *it;
    const double tau = std::clamp(t - s.t0, 0.0, s.duration);
    const double w = std::numbers::pi / s.duration;
    const double dv = s.v1 - s.v0;
    x = s.x0 + s.v0 * tau + 0.5 * dv * (tau - std::sin(w * tau) / w);
    xd = s.v0 + 0.5 * dv * (1.0 - std::cos(w * tau));
    xdd = 0.5 * dv * w * std::sin(w * tau);
    if (t - s.t0 > s.duration) x += s.v1 * (t - s.t0 - s.duration);  // past the end: cruise
  }

 private:
  std::vector<VelocitySegment> segments_;
  double t_, x_ = 0.0, v_ = 0.0;
};

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// Point-to-point moves with a bell-shaped velocity (two raised-cosine halves)
// to random targets, mostly separated by holds at rest: how a surgeon
// positions an instrument.
VelocityProfile surgeon_profile(double t_start, double t_end, double amplitude,
                                std::mt19937_64& rng) {
  VelocityProfile p(t_start);
  p.go(0.0, 0.3);
  while (p.t() < t_end) {
    if (uniform(rng, 0.0, 1.0) < 0.7) p.go(0.0, uniform(rng, 0.2, 1.5));
    double target = uniform(rng, -amplitude, amplitude);
    if (std::fabs(target - p.x()) < 0.1 * amplitude)
      target = p.x() > 0.0 ? p.x() - 0.5 * amplitude : p.x() + 0.5 * amplitude;
    const double duration = uniform(rng, 0.6, 2.0);
    const double peak = 2.0 * (target - p.x()) / duration;
    p.go(peak, 0.5 * duration);
    p.go(0.0, 0.5 * duration);
  }
  return p;
}

// Constant-speed strokes (0.4-1.5 rad/s) joined by reversals of 40-120 ms.
VelocityProfile reversal_profile(double t_start, double t_end, double amplitude,
                                 std::mt19937_64& rng) {
  VelocityProfile p(t_start);
  double direction = 1.0;
  while (p.t() < t_end) {
    const double v = direction * uniform(rng, 0.4, 1.5);
    p.go(v, uniform(rng, 0.04, 0.12));
    const double target = direction * uniform(rng, 0.3, 1.0) * amplitude;
    p.go(v, std::max(0.05, (target - p.x()) / v));
    direction = -direction;
  }
  return p;
}

// Slow motion: speed levels of 5-50 mrad/s (sometimes a pause), reached over
// 0.3-1.5 s and held for 0.5-3 s, heading back when near the end of travel.
VelocityProfile creep_profile(double t_start, double t_end, double amplitude,
                              std::mt19937_64& rng) {
  VelocityProfile p(t_start);
  while (p.t() < t_end) {
    double v = 0.0;
    if (uniform(rng, 0.0, 1.0) > 0.2) {
      v = uniform(rng, 0.005, 0.05) * (uniform(rng, 0.0, 1.0) < 0.5 ? -1.0 : 1.0);
      if (std::fabs(p.x()) > 0.5 * amplitude && v * p.x() > 0.0) v = -v;
    }
    p.go(v, uniform(rng, 0.3, 1.5));
    p.go(v, uniform(rng, 0.5, 3.0));
  }
  return p;
}

}  // namespace

std::optional<MotionKind> motion_kind_from_name(std::string_view name) {
  for (MotionKind k :
       {MotionKind::kMultisine, MotionKind::kSurgeon, MotionKind::kReversals, MotionKind::kCreep}) {
    if (name == motion_kind_name(k)) return k;
  }
  return std::nullopt;
}

const char* motion_kind_name(MotionKind kind) {
  return realtime::enum_name<MotionKind::kCreep>(kind,
                                                 {"multisine", "surgeon", "reversals", "creep"})
      .data();
}

SyntheticData make_synthetic(const FrictionModel& truth, const SyntheticConfig& c) {
  if (!(c.duration_s > 0.0) || !(c.rate_hz > 0.0) || !(c.radius_m > 0.0) || c.components < 1 ||
      !(c.f_low_hz > 0.0) || !(c.f_high_hz >= c.f_low_hz) || c.substeps < 1 ||
      c.torque_noise < 0.0 || c.quantum < 0.0 || !(c.jitter_s >= 0.0) ||
      !(c.jitter_s < 0.5 / c.rate_hz) || !(c.drop_fraction >= 0.0) || !(c.drop_fraction <= 0.5) ||
      !(c.tremor_rad >= 0.0) || !(c.tremor_hz > 0.0) || !std::isfinite(c.drift_acc)) {
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
  // The other kinds and the sampling faults draw from their own streams, so
  // the multi-sine recordings stay what they were for a given seed.
  std::mt19937_64 path_rng(c.seed * 0x9E3779B97F4A7C15ULL + 1);
  std::mt19937_64 sampling_rng(c.seed * 0x9E3779B97F4A7C15ULL + 2);
  std::optional<VelocityProfile> profile;
  switch (c.motion) {
    case MotionKind::kMultisine:
      break;
    case MotionKind::kSurgeon:
      profile = surgeon_profile(-fade, c.duration_s + 1.0, c.amplitude_rad, path_rng);
      break;
    case MotionKind::kReversals:
      profile = reversal_profile(-fade, c.duration_s + 1.0, c.amplitude_rad, path_rng);
      break;
    case MotionKind::kCreep:
      profile = creep_profile(-fade, c.duration_s + 1.0, c.amplitude_rad, path_rng);
      break;
  }
  auto model = truth.clone();
  model->reset();

  SyntheticData out;
  Recording& rec = out.recording;
  rec.source = "synthetic(seed " + std::to_string(c.seed) + ")";
  rec.radius_m = c.radius_m;
  rec.t.reserve(n);
  rec.x_in.reserve(n);
  rec.tau_in.reserve(n);
  rec.tau_out.reserve(n);
  out.true_friction.reserve(n);

  const auto state_at = [&](double t, double f_prev) {
    double s, sd, sdd, e, ed, edd, l, ld, ldd;
    envelope(t, fade, e, ed, edd);
    load.eval(t, l, ld, ldd);
    Motion m;
    m.t = t;
    if (profile) {
      profile->eval(t, m.x, m.xd, m.xdd);  // starts at rest: needs no fade
    } else {
      motion.eval(t, s, sd, sdd);
      m.x = e * s;
      m.xd = ed * s + e * sd;
      m.xdd = edd * s + 2.0 * ed * sd + e * sdd;
    }
    if (c.tremor_rad > 0.0) {
      const double w = kTwoPi * c.tremor_hz;
      m.x += c.tremor_rad * std::sin(w * t);
      m.xd += c.tremor_rad * w * std::cos(w * t);
      m.xdd -= c.tremor_rad * w * w * std::sin(w * t);
    }
    if (c.drift_acc != 0.0) {
      const double since = t + fade;  // from the start of the pre-roll
      m.x += 0.5 * c.drift_acc * since * since;
      m.xd += c.drift_acc * since;
      m.xdd += c.drift_acc;
    }
    m.acc_sign = sign_of(m.xdd);
    const double tau_out = c.load_offset + c.load_amplitude * e * l;
    m.load = std::fabs(tau_out + c.radius_m * f_prev) / c.radius_m;
    // The signed drive tau_in / R, as a recording gives it: a model that
    // reads the distal load takes it as drive less its own friction.
    m.drive = (tau_out + c.radius_m * f_prev) / c.radius_m;
    return std::pair{m, tau_out};
  };

  // Pre-roll: the true model runs through the fade-in from rest, unrecorded.
  // With jitter, sample i is taken at i dt + U(-jitter, jitter); the plant runs
  // on between the instants, and a dropped sample is simply not recorded.
  double f = 0.0;
  const auto pre = static_cast<long>(std::ceil(fade * c.rate_hz));
  const double h = dt / c.substeps;
  std::uniform_real_distribution<double> jitter(-c.jitter_s, c.jitter_s);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double t_prev = static_cast<double>(-pre) * dt;
  for (long i = -pre; i < static_cast<long>(n); ++i) {
    double t = static_cast<double>(i) * dt;
    const long first = c.from_rest ? -pre : 0;
    if (i > first && c.jitter_s > 0.0) t += jitter(sampling_rng);
    if (i > -pre) {
      for (int k = 1; k <= c.substeps; ++k) {
        const double tk = c.jitter_s > 0.0 ? t_prev + k * (t - t_prev) / c.substeps
                                           : static_cast<double>(i - 1) * dt + k * h;
        const double hk = c.jitter_s > 0.0 ? (t - t_prev) / c.substeps : h;
        f = model->step(state_at(tk, f).first, hk);
      }
    }
    t_prev = t;
    if (i < first) continue;
    const auto [m, tau_out] = state_at(t, f);
    const double tau_out_seen = tau_out + noise(rng);
    const double tau_in_seen = tau_out + c.radius_m * f + noise(rng);
    if (c.drop_fraction > 0.0 && i > first && unit(sampling_rng) < c.drop_fraction) continue;
    rec.t.push_back(t);
    rec.x_in.push_back(c.quantum > 0.0 ? std::round(m.x / c.quantum) * c.quantum : m.x);
    rec.tau_out.push_back(tau_out_seen);
    rec.tau_in.push_back(tau_in_seen);
    if (c.exact_derivatives) {
      rec.xd_in.push_back(m.xd);
      rec.xdd_in.push_back(m.xdd);
    }
    out.true_friction.push_back(f);
  }
  return out;
}

}  // namespace tsmh::estimator
