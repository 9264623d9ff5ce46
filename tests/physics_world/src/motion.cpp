#include "physics_world/motion.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <random>

namespace tsmh::physics_world {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

struct Names {
  MotionKind kind;
  const char* name;
};
constexpr std::array<Names, 6> kNames{{{MotionKind::kMultisine, "multisine"},
                                       {MotionKind::kSurgeon, "surgeon"},
                                       {MotionKind::kReversals, "reversals"},
                                       {MotionKind::kCreep, "creep"},
                                       {MotionKind::kPalpation, "palpation"},
                                       {MotionKind::kReroute, "reroute"}}};

class Draw {
 public:
  explicit Draw(std::uint64_t seed) : rng_(seed) {}
  double operator()(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng_);
  }
  bool chance(double p) { return (*this)(0.0, 1.0) < p; }

 private:
  std::mt19937_64 rng_;
};

// Builds a knot path: each go() adds a knot `duration` after the last.
class Builder {
 public:
  Builder() { path_.knots.push_back({0.0, 0.0, 0.0, 0.0}); }
  void go(double duration, double x, double v = 0.0) {
    const auto& last = path_.knots.back();
    path_.knots.push_back({last.t + duration, x, v, 0.0});
  }
  // At a constant velocity for `duration` (a straight line is a quintic too).
  void cruise(double duration) {
    const auto& last = path_.knots.back();
    go(duration, last.x + last.v * duration, last.v);
  }
  void hold(double duration) { go(duration, x(), 0.0); }
  double t() const { return path_.knots.back().t; }
  double x() const { return path_.knots.back().x; }
  double v() const { return path_.knots.back().v; }
  Path take() { return std::move(path_); }

 private:
  Path path_;
};

Path multisine(double duration, double peak, int components, double f_lo, double f_hi, double fade,
               Draw& draw) {
  Path p;
  p.fade_s = fade;
  for (int k = 0; k < components; ++k) {
    const double f =
        f_lo * std::pow(f_hi / f_lo, components == 1 ? 0.0 : double(k) / (components - 1));
    p.freq.push_back(f);
    p.amp.push_back(1.0 / std::sqrt(f));
    p.phase.push_back(draw(0.0, kTwoPi));
  }
  double largest = 0.0;
  for (double t = 0.0; t <= duration + 1.0; t += 0.005)
    largest = std::max(largest, std::fabs(p.at(t).x));
  for (double& a : p.amp)
    a *= peak / largest;
  return p;
}

Path surgeon(double duration, Draw& draw) {
  Builder b;
  b.hold(draw(0.2, 0.8));
  while (b.t() < duration + 1.0) {
    if (draw.chance(0.6)) b.hold(draw(0.2, 1.5));
    const double target = draw(-1.0, 1.0);
    if (draw.chance(0.3)) {
      // Two moves blended through a via point without stopping.
      const double via = 0.5 * (b.x() + target) + draw(-0.2, 0.2);
      const double d1 = draw(0.4, 1.2), d2 = draw(0.4, 1.2);
      const double v_via = (target - b.x()) / (d1 + d2);
      b.go(d1, via, v_via);
      b.go(d2, target, 0.0);
    } else {
      b.go(draw(0.6, 2.0), target, 0.0);
    }
  }
  return b.take();
}

Path reversals(double duration, Draw& draw) {
  Builder b;
  b.hold(0.3);
  double direction = draw.chance(0.5) ? 1.0 : -1.0;
  double v = direction * draw(0.4, 1.5);
  double ramp = 0.15;
  b.go(ramp, v * ramp / 2.0, v);
  while (b.t() < duration + 1.0) {
    const double target = direction * draw(0.3, 1.0);
    const double cruise = std::max(0.02, (target - b.x()) / v);
    b.cruise(cruise);
    // A fast reversal: the average of the two speeds over the turn.
    direction = -direction;
    const double v_new = direction * draw(0.4, 1.5);
    const double turn = draw(0.04, 0.15);
    b.go(turn, b.x() + 0.5 * (v + v_new) * turn, v_new);
    v = v_new;
  }
  return b.take();
}

Path creep(double duration, Draw& draw) {
  Builder b;
  b.hold(0.3);
  while (b.t() < duration + 1.0) {
    double v = 0.0;
    if (!draw.chance(0.2)) {
      const double sign = b.x() > 0.6 ? -1.0 : b.x() < -0.6 ? 1.0 : (draw.chance(0.5) ? 1.0 : -1.0);
      v = sign * draw(0.005, 0.05);
    }
    const double change = draw(0.3, 1.5);
    b.go(change, b.x() + 0.5 * (b.v() + v) * change, v);
    b.cruise(draw(0.5, 3.0));
  }
  return b.take();
}

Path palpation(double duration, const TipParams& tip, Draw& draw) {
  Builder b;
  b.hold(0.3);
  const double surface = tip.tissue_surface_rad;
  b.go(1.5, surface - 0.2, 0.0);
  while (b.t() < duration + 1.0) {
    if (draw.chance(0.15)) {
      // Over to the grasped object and back.
      b.go(draw(1.0, 2.0), tip.grasp_surface_rad - draw(0.05, 0.3), 0.0);
      b.hold(draw(0.2, 0.8));
      b.go(draw(1.0, 2.0), surface - draw(0.05, 0.3), 0.0);
      continue;
    }
    // Into the tissue past the surface (x_in leads x_out by the tendons'
    // stretch), a hold, and back out.
    b.go(draw(0.4, 1.2), surface + draw(0.1, 0.45), 0.0);
    b.hold(draw(0.2, 1.0));
    b.go(draw(0.4, 1.2), surface - draw(0.05, 0.3), 0.0);
    b.hold(draw(0.1, 0.5));
  }
  return b.take();
}

double fade_value(double s) {
  return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s);
}
double fade_slope(double s) {
  return 30.0 * s * s * (1.0 - s) * (1.0 - s);
}
double fade_curve(double s) {
  return 60.0 * s * (1.0 - s) * (1.0 - 2.0 * s);
}

}  // namespace

std::optional<MotionKind> motion_kind_from_name(std::string_view name) {
  for (const auto& n : kNames)
    if (name == n.name) return n.kind;
  return std::nullopt;
}

const char* motion_kind_name(MotionKind kind) {
  for (const auto& n : kNames)
    if (n.kind == kind) return n.name;
  return "?";
}

std::vector<MotionKind> all_motion_kinds() {
  std::vector<MotionKind> out;
  for (const auto& n : kNames)
    out.push_back(n.kind);
  return out;
}

PathPoint Path::at(double t) const {
  if (knots.empty()) {
    double m = 0.0, md = 0.0, mdd = 0.0;
    for (std::size_t k = 0; k < amp.size(); ++k) {
      const double w = kTwoPi * freq[k];
      const double arg = w * t + phase[k];
      m += amp[k] * std::sin(arg);
      md += amp[k] * w * std::cos(arg);
      mdd -= amp[k] * w * w * std::sin(arg);
    }
    if (fade_s <= 0.0 || t >= fade_s) return {m, md, mdd};
    if (t <= 0.0) return {0.0, 0.0, 0.0};
    const double s = t / fade_s;
    const double w = fade_value(s), wd = fade_slope(s) / fade_s,
                 wdd = fade_curve(s) / (fade_s * fade_s);
    return {w * m, wd * m + w * md, wdd * m + 2.0 * wd * md + w * mdd};
  }
  if (t <= knots.front().t) return {knots.front().x, 0.0, 0.0};
  const auto it = std::upper_bound(knots.begin(), knots.end(), t,
                                   [](double value, const Knot& k) { return value < k.t; });
  if (it == knots.end()) {
    const Knot& k = knots.back();
    return {k.x + k.v * (t - k.t), k.v, 0.0};
  }
  const Knot& k0 = *(it - 1);
  const Knot& k1 = *it;
  const double T = k1.t - k0.t;
  const double dp = k1.x - k0.x;
  const double c0 = k0.x, c1 = k0.v, c2 = 0.5 * k0.a;
  const double c3 = (20.0 * dp - (8.0 * k1.v + 12.0 * k0.v) * T - (3.0 * k0.a - k1.a) * T * T) /
                    (2.0 * T * T * T);
  const double c4 =
      (-30.0 * dp + (14.0 * k1.v + 16.0 * k0.v) * T + (3.0 * k0.a - 2.0 * k1.a) * T * T) /
      (2.0 * T * T * T * T);
  const double c5 =
      (12.0 * dp - 6.0 * (k1.v + k0.v) * T - (k0.a - k1.a) * T * T) / (2.0 * T * T * T * T * T);
  const double s = t - k0.t;
  const double x = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))));
  const double xd = c1 + s * (2.0 * c2 + s * (3.0 * c3 + s * (4.0 * c4 + s * 5.0 * c5)));
  const double xdd = 2.0 * c2 + s * (6.0 * c3 + s * (12.0 * c4 + s * 20.0 * c5));
  return {x, xd, xdd};
}

Path make_path(MotionKind kind, double duration_s, const TipParams& tip, std::uint64_t seed) {
  Draw draw(seed * 0xD1B54A32D192ED03ULL + static_cast<std::uint64_t>(kind) + 11);
  switch (kind) {
    case MotionKind::kMultisine:
      return multisine(duration_s, 1.0, 7, 0.1, 1.0, 1.0, draw);
    case MotionKind::kSurgeon:
    case MotionKind::kReroute:
      return surgeon(duration_s, draw);
    case MotionKind::kReversals:
      return reversals(duration_s, draw);
    case MotionKind::kCreep:
      return creep(duration_s, draw);
    case MotionKind::kPalpation:
      return palpation(duration_s, tip, draw);
  }
  return {};
}

Path make_external_torque(double duration_s, double peak, std::uint64_t seed) {
  Draw draw(seed * 0x8CB92BA72F3D8DD7ULL + 5);
  return multisine(duration_s, peak, 3, 0.03, 0.25, 2.0, draw);
}

Reroute make_reroute(std::uint64_t seed) {
  Draw draw(seed * 0xA24BAED4963EE407ULL + 3);
  Reroute r;
  r.at_s = draw(12.0, 28.0);
  r.ramp_s = draw(0.5, 2.0);
  r.scale1 = draw(0.6, 1.5);
  r.scale2 = draw(0.6, 1.5);
  return r;
}

}  // namespace tsmh::physics_world
