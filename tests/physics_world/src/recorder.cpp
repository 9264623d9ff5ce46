#include "physics_world/recorder.hpp"

#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

namespace tsmh::physics_world {

namespace {

double quantize(double v, double q) {
  return q > 0.0 ? q * std::round(v / q) : v;
}

}  // namespace

WorldRecording record(const WorldParams& world, const RunConfig& run) {
  if (!(run.duration_s > 0.0) || !(run.rate_hz > 0.0) || !(run.sensors.encoder_counts >= 0.0) ||
      !(run.sensors.load_cell_noise_n >= 0.0) || !(run.sensors.tip_torque_noise_n_m >= 0.0))
    throw std::invalid_argument(
        "physics_world::record: duration, rate, encoder counts and noises must be positive");
  WorldRecording out;
  out.world = world;
  if (run.kind == MotionKind::kReroute) out.world.reroute = make_reroute(run.motion_seed);
  World w(out.world);
  const Path path = make_path(run.kind, run.duration_s, out.world.tip, run.motion_seed);
  const Path external =
      make_external_torque(run.duration_s, out.world.tip.external_peak_n_m, run.motion_seed);
  std::mt19937_64 noise_rng(run.motion_seed * 0xBF58476D1CE4E5B9ULL + world.seed + 7);
  std::normal_distribution<double> unit(0.0, 1.0);

  const double r = out.world.tip.radius_m;
  const double q =
      run.sensors.encoder_counts > 0.0 ? 2.0 * std::numbers::pi / run.sensors.encoder_counts : 0.0;
  const auto samples = static_cast<std::size_t>(std::floor(run.duration_s * run.rate_hz)) + 1;
  const double period = 1.0 / run.rate_hz;
  const double dt = period / out.world.substeps;
  estimator::Recording& rec = out.recording;
  rec.source = std::string("physics world ") + std::to_string(world.seed) + ", " +
               motion_kind_name(run.kind) + " " + std::to_string(run.motion_seed);
  rec.radius_m = r;
  for (auto* v :
       {&rec.t, &rec.x_in, &rec.tau_in, &rec.tau_out, &rec.x_out, &rec.T1, &rec.T3, &rec.xd_in,
        &rec.xdd_in, &out.friction_true, &out.tau_in_true, &out.tau_out_true, &out.contact})
    v->reserve(samples);

  double t = 0.0;
  for (std::size_t i = 0; i < samples; ++i) {
    if (i > 0) {
      const double t0 = static_cast<double>(i - 1) * period;
      for (int k = 1; k <= out.world.substeps; ++k) {
        const double tk = t0 + k * dt;
        w.apply_route(tk);
        const PathPoint p = path.at(tk);
        w.step(dt, p.x, p.xd, p.xdd, external.at(tk).x);
      }
    }
    t = static_cast<double>(i) * period;
    const TipState s = w.state();
    const double t1 = s.T1 + run.sensors.load_cell_noise_n * unit(noise_rng);
    const double t3 = s.T3 + run.sensors.load_cell_noise_n * unit(noise_rng);
    rec.t.push_back(t);
    rec.x_in.push_back(quantize(s.x_in, q));
    rec.xd_in.push_back(s.xd_in);
    rec.xdd_in.push_back(s.xdd_in);
    rec.T1.push_back(t1);
    rec.T3.push_back(t3);
    rec.tau_in.push_back(r * (t1 - t3));
    out.tau_in_true.push_back(r * (s.T1 - s.T3));
    out.tau_out_true.push_back(r * (s.T2 - s.T4));
    rec.tau_out.push_back(out.tau_out_true.back() +
                          run.sensors.tip_torque_noise_n_m * unit(noise_rng));
    rec.x_out.push_back(quantize(s.x_out, q));
    out.friction_true.push_back((s.T1 - s.T3) - (s.T2 - s.T4));
    out.contact.push_back(s.in_contact() ? 1.0 : 0.0);
  }
  return out;
}

estimator::Table to_table(const WorldRecording& r, bool with_derivatives) {
  estimator::Recording rec = r.recording;
  if (!with_derivatives) {
    rec.xd_in.clear();
    rec.xdd_in.clear();
  }
  estimator::Table table = estimator::recording_to_table(rec);
  table.set("friction_true", r.friction_true);
  table.set("tau_in_true", r.tau_in_true);
  table.set("tau_out_true", r.tau_out_true);
  table.set("contact", r.contact);
  table.meta["physics_world_seed"] = std::to_string(r.world.seed);
  return table;
}

void write_csv(const WorldRecording& r, const std::filesystem::path& path, bool with_derivatives) {
  estimator::write_csv_table(to_table(r, with_derivatives), path);
}

}  // namespace tsmh::physics_world
