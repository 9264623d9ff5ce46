#include "haptics/evaluation.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>

#include "estimator/atomic_file.hpp"
#include "realtime/joint_names.hpp"

namespace tsmh::haptics {
namespace {

struct LineFit {
  double slope = std::nan("");
  double sse = 0.0;
};

LineFit fit_line(const std::vector<double>& x, const std::vector<double>& y) {
  LineFit f;
  const std::size_t n = x.size();
  if (n < 3) return f;
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(n);
  const double my = std::accumulate(y.begin(), y.end(), 0.0) / static_cast<double>(n);
  double sxx = 0, sxy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sxx += (x[i] - mx) * (x[i] - mx);
    sxy += (x[i] - mx) * (y[i] - my);
  }
  if (!(sxx > 0.0)) return f;
  f.slope = sxy / sxx;
  for (std::size_t i = 0; i < n; ++i) {
    const double e = y[i] - my - f.slope * (x[i] - mx);
    f.sse += e * e;
  }
  return f;
}

bool enabled_with_truth(const TraceRow& r, std::size_t j) {
  return r.state == static_cast<std::int32_t>(LoopState::kEnabled) &&
         std::isfinite(r.joints[j].true_tau_out);
}

// Splits contact samples of joint j at the indentation where the force
// against indentation changes slope most (two-segment least squares): the
// edge of the hard inclusion under the soft layer.
double find_boundary(const Trace& trace, std::size_t j) {
  std::vector<std::pair<double, double>> pts;
  for (std::size_t i = 0; i < trace.size(); ++i) {
    const TraceRow row = trace[i];  // by value: a stored trace is decoded row by row
    const auto& q = row.joints[j];
    if (std::isfinite(q.indentation) && q.indentation > 0.0 && std::isfinite(q.contact_force))
      pts.emplace_back(q.indentation, q.contact_force);
  }
  if (pts.size() < 50) return std::nan("");
  std::sort(pts.begin(), pts.end());
  double best = std::nan(""), best_sse = std::numeric_limits<double>::infinity();
  for (int k = 1; k < 20; ++k) {
    const std::size_t cut = pts.size() * static_cast<std::size_t>(k) / 20;
    std::vector<double> x1, y1, x2, y2;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      auto& x = i < cut ? x1 : x2;
      auto& y = i < cut ? y1 : y2;
      x.push_back(pts[i].first);
      y.push_back(pts[i].second);
    }
    const LineFit a = fit_line(x1, y1), b = fit_line(x2, y2);
    if (std::isnan(a.slope) || std::isnan(b.slope)) continue;
    if (a.sse + b.sse < best_sse) {
      best_sse = a.sse + b.sse;
      best = pts[cut].first;
    }
  }
  return best;
}

}  // namespace

double slope(const std::vector<double>& x, const std::vector<double>& y) {
  return fit_line(x, y).slope;
}

namespace {

struct PhaseSamples {
  std::vector<double> qm, tm, xs, ts;
  void append(const PhaseSamples& o) {
    qm.insert(qm.end(), o.qm.begin(), o.qm.end());
    tm.insert(tm.end(), o.tm.begin(), o.tm.end());
    xs.insert(xs.end(), o.xs.begin(), o.xs.end());
    ts.insert(ts.end(), o.ts.begin(), o.ts.end());
  }
};

Stiffness stiffness_of(const PhaseSamples& p, double gain, double position_scale) {
  Stiffness s;
  s.samples = p.qm.size();
  s.perceived = std::fabs(slope(p.qm, p.tm)) / gain;
  s.truth = std::fabs(slope(p.xs, p.ts));
  s.ideal = std::fabs(slope(p.qm, p.ts)) / position_scale;
  s.reached =
      s.samples >= kMinStiffnessSamples && std::isfinite(s.perceived) && std::isfinite(s.truth);
  return s;
}

// Marks a phase not reached: its figures are not printed as if they were.
void not_reached(Stiffness& s, std::string why) {
  s.reached = false;
  s.why = std::move(why);
  s.perceived = s.truth = s.ideal = std::nan("");
}

std::string too_few(std::size_t n) {
  return "only " + std::to_string(n) + " contact ticks in this phase (at least " +
         std::to_string(kMinStiffnessSamples) + " needed for a slope)";
}

}  // namespace

Discrimination discriminate(const Trace& trace, const ServerConfig& config, int joint) {
  Discrimination d;
  d.joint = joint;
  if (d.joint >= 0) {
    const auto j = static_cast<std::size_t>(d.joint);
    d.boundary_m = find_boundary(trace, j);
    d.force_scale = config.loop.force[j].scale;
    d.force_sign = config.loop.force[j].sign;
    d.position_scale = config.loop.position[j].scale;
    const double gain = d.force_scale * d.position_scale;
    PhaseSamples phase[2];
    for (std::size_t i = 0; i < trace.size(); ++i) {
      const auto& row = trace[i];
      if (!enabled_with_truth(row, j)) continue;
      const auto& q = row.joints[j];
      if (!(q.indentation > 0.0) || !std::isfinite(q.true_x_out)) continue;
      d.deepest_m = std::max(d.deepest_m, q.indentation);
      const int cls = std::isfinite(d.boundary_m) && q.indentation > d.boundary_m ? 1 : 0;
      phase[cls].qm.push_back(q.master_q);
      phase[cls].tm.push_back(q.torque_cmd);
      phase[cls].xs.push_back(q.true_x_out);
      phase[cls].ts.push_back(q.true_tau_out);
    }
    d.soft = stiffness_of(phase[0], gain, d.position_scale);
    d.hard = stiffness_of(phase[1], gain, d.position_scale);
    // The split always finds a "best" cut; it is the nodule's edge only when
    // the true slope beyond it is clearly steeper. Otherwise every contact
    // tick is the soft layer's, and the nodule was not reached.
    if (!(d.hard.truth > kNoduleSlopeRatio * d.soft.truth) || d.hard.samples < 50) {
      phase[0].append(phase[1]);
      d.soft = stiffness_of(phase[0], gain, d.position_scale);
      d.hard = Stiffness{};
      char b[160];
      std::snprintf(b, sizeof b,
                    "no stiffer layer under the soft one in this run (deepest indentation %.1f mm)",
                    d.deepest_m * 1e3);
      not_reached(d.hard, b);
      d.boundary_m = std::nan("");
    } else if (!d.hard.reached) {
      not_reached(d.hard, too_few(d.hard.samples));
    }
    if (!d.soft.reached) not_reached(d.soft, too_few(d.soft.samples));
  }
  return d;
}

JointEvaluation evaluate_joint(const Trace& trace, const ServerConfig& config, std::size_t j) {
  JointEvaluation je;
  je.name = config.joints[j].name;
  double se_est = 0, se_naive = 0, phantom = 0, phantom_naive = 0;
  double se_est_contact = 0, se_naive_contact = 0, se_est_free = 0, se_naive_free = 0;
  const double force_scale = config.loop.force[j].scale;
  for (std::size_t i = 0; i < trace.size(); ++i) {
    const auto& row = trace[i];
    if (!enabled_with_truth(row, j)) continue;
    const auto& q = row.joints[j];
    if (std::isfinite(q.indentation))
      je.deepest_indentation = std::max(je.deepest_indentation, q.indentation);
    if (!std::isfinite(q.tau_out_est) || !std::isfinite(q.tau_in)) continue;
    se_est += (q.tau_out_est - q.true_tau_out) * (q.tau_out_est - q.true_tau_out);
    se_naive += (q.tau_in - q.true_tau_out) * (q.tau_in - q.true_tau_out);
    je.true_peak = std::max(je.true_peak, std::fabs(q.true_tau_out));
    ++je.samples;
    const double e_est = q.tau_out_est - q.true_tau_out, e_naive = q.tau_in - q.true_tau_out;
    if (std::fabs(q.true_tau_out) < kPhantomThreshold && std::isfinite(q.torque_cmd)) {
      phantom += q.torque_cmd * q.torque_cmd;
      phantom_naive += force_scale * force_scale * q.tau_in * q.tau_in;
      se_est_free += e_est * e_est;
      se_naive_free += e_naive * e_naive;
      ++je.free_samples;
    }
    const bool contact = std::isfinite(q.indentation)
                             ? q.indentation > 0.0
                             : std::fabs(q.true_tau_out) >= kPhantomThreshold;
    if (contact) {
      se_est_contact += e_est * e_est;
      se_naive_contact += e_naive * e_naive;
      ++je.contact_samples;
    }
  }
  if (je.contact_samples) {
    const auto n = static_cast<double>(je.contact_samples);
    je.contact_rmse_estimated = std::sqrt(se_est_contact / n);
    je.contact_rmse_naive = std::sqrt(se_naive_contact / n);
    je.contact_ratio =
        je.contact_rmse_naive > 0 ? je.contact_rmse_estimated / je.contact_rmse_naive : 0.0;
  }
  if (je.samples) {
    je.rmse_estimated = std::sqrt(se_est / static_cast<double>(je.samples));
    je.rmse_naive = std::sqrt(se_naive / static_cast<double>(je.samples));
    je.ratio = je.rmse_naive > 0 ? je.rmse_estimated / je.rmse_naive : 0.0;
  }
  if (je.free_samples) {
    je.free_rmse_estimated = std::sqrt(se_est_free / static_cast<double>(je.free_samples));
    je.free_rmse_naive = std::sqrt(se_naive_free / static_cast<double>(je.free_samples));
    je.phantom_rendered = std::sqrt(phantom / static_cast<double>(je.free_samples));
    je.phantom_naive = std::sqrt(phantom_naive / static_cast<double>(je.free_samples));
    je.phantom_ratio = je.phantom_naive > 0 ? je.phantom_rendered / je.phantom_naive : 0.0;
  }
  return je;
}

EvaluationReport evaluate(const HapticLoop& loop, const Trace& trace, const ServerConfig& config) {
  EvaluationReport r;
  r.nominal_rate_hz = config.loop.rate_hz;
  r.rate_hz = loop.measured_rate_hz();
  r.jitter = loop.lateness().summary();
  r.compute = loop.compute().summary();
  r.overruns = loop.counters().overruns;
  r.duration_s = trace.size() ? trace[trace.size() - 1].t : 0.0;
  r.feedback = std::string(to_string(config.loop.source));
  const auto joints = static_cast<std::size_t>(config.loop.joints);

  // The joint that pressed the tissue deepest is the one whose stiffness is felt.
  double deepest = 0.0;
  for (std::size_t j = 0; j < joints; ++j) {
    r.joints.push_back(evaluate_joint(trace, config, j));
    if (r.joints.back().deepest_indentation > deepest) {
      deepest = r.joints.back().deepest_indentation;
      r.discrimination.joint = static_cast<int>(j);
    }
  }

  r.discrimination = discriminate(trace, config, r.discrimination.joint);
  return r;
}

std::string report_to_json(const EvaluationReport& r) {
  using nlohmann::json;
  const auto num = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
  json joints = json::array();
  for (const auto& j : r.joints)
    joints.push_back({{"name", j.name},
                      {"samples", j.samples},
                      {"rmse_estimated", num(j.rmse_estimated)},
                      {"rmse_naive", num(j.rmse_naive)},
                      {"ratio", num(j.ratio)},
                      {"true_peak", num(j.true_peak)},
                      // The contract's names for the free-motion figures;
                      // free_motion has them with their threshold and counts.
                      {"phantom_rms", num(j.phantom_rendered)},
                      {"phantom_ratio", num(j.phantom_ratio)},
                      {"free_motion",
                       {{"threshold_nm", kPhantomThreshold},
                        {"samples", j.free_samples},
                        {"phantom_rendered_nm", num(j.phantom_rendered)},
                        {"phantom_naive_nm", num(j.phantom_naive)},
                        {"phantom_ratio", num(j.phantom_ratio)},
                        {"rmse_estimated_nm", num(j.free_rmse_estimated)},
                        {"rmse_naive_nm", num(j.free_rmse_naive)}}},
                      {"in_contact",
                       {{"samples", j.contact_samples},
                        {"rmse_estimated_nm", num(j.contact_rmse_estimated)},
                        {"rmse_naive_nm", num(j.contact_rmse_naive)},
                        {"ratio", num(j.contact_ratio)}}}});
  const auto& d = r.discrimination;
  json doc = {{"loop",
               {{"rate_hz", num(r.rate_hz)},
                {"nominal_rate_hz", num(r.nominal_rate_hz)},
                {"jitter_us",
                 {{"p50", r.jitter.p50_us},
                  {"p99", r.jitter.p99_us},
                  {"p999", r.jitter.p999_us},
                  {"max", r.jitter.max_us},
                  {"mean", r.jitter.mean_us}}},
                {"compute_us",
                 {{"p50", r.compute.p50_us}, {"p99", r.compute.p99_us}, {"max", r.compute.max_us}}},
                {"overruns", r.overruns},
                {"duration_s", num(r.duration_s)}}},
              {"feedback", r.feedback},
              {"joints", joints},
              {"discrimination",
               {{"joint", d.joint},
                {"boundary_m", num(d.boundary_m)},
                {"soft_stiffness", num(d.soft.perceived)},
                {"hard_stiffness", num(d.hard.perceived)},
                {"soft_true", num(d.soft.truth)},
                {"hard_true", num(d.hard.truth)},
                {"soft_samples", d.soft.samples},
                {"hard_samples", d.hard.samples},
                {"soft_reached", d.soft.reached},
                {"hard_reached", d.hard.reached},
                {"deepest_m", num(d.deepest_m)},
                {"soft_ideal", num(d.soft.ideal)},
                {"hard_ideal", num(d.hard.ideal)},
                {"force_scale", num(d.force_scale)},
                {"force_sign", num(d.force_sign)},
                {"position_scale", num(d.position_scale)},
                {"units", "N m/rad, slave joint space"}}}};
  json events = json::array();
  for (const auto& e : r.calibration)
    events.push_back({{"t_s", e.t_s},
                      {"kind", e.kind},
                      {"joint", e.joint},
                      {"scale", num(e.scale)},
                      {"scale_positive", num(e.scale_positive)},
                      {"scale_negative", num(e.scale_negative)},
                      {"reason", e.reason}});
  doc["calibration"] = {{"events", events},
                        {"friction_scale", r.friction_scale},
                        {"friction_scale_positive", r.friction_scale_positive},
                        {"friction_scale_negative", r.friction_scale_negative}};
  return doc.dump(2) + "\n";
}

void write_report(const EvaluationReport& report, const std::string& path) {
  estimator::write_text_atomically(path, report_to_json(report));
}

std::string format_stiffness(const Discrimination& d, double rate_hz) {
  // How far each felt stiffness is from the truth, in %: what a surgeon
  // would misjudge (the same for the perfect estimate, for scale).
  const auto off = [](double felt, double truth) {
    char b[48];
    if (std::isfinite(felt) && std::isfinite(truth) && truth > 0)
      std::snprintf(b, sizeof b, "%+.0f %%", 100.0 * (felt - truth) / truth);
    else
      std::snprintf(b, sizeof b, "n/a");
    return std::string(b);
  };
  const double hz = rate_hz > 0.0 ? rate_hz : 1000.0;
  std::string s;
  char line[640];
  std::snprintf(line, sizeof line,
                "stiffness felt pressing %s, in N m/rad of the slave joint (the master's "
                "torque / force scale %g, per master rad x position scale %g), against the "
                "tissue's true stiffness:\n",
                realtime::joint_name(static_cast<std::size_t>(d.joint)).c_str(), d.force_scale,
                d.position_scale);
  s += line;
  const auto row = [&](const char* name, const Stiffness& st) {
    if (!st.reached) {
      std::snprintf(line, sizeof line, "  %-11s not reached: %s\n", name, st.why.c_str());
    } else {
      std::snprintf(line, sizeof line,
                    "  %-11s felt %.3f, true %.3f: %s; a perfect estimate %.3f (%s); from %zu "
                    "contact ticks (%.1f s)\n",
                    name, st.perceived, st.truth, off(st.perceived, st.truth).c_str(), st.ideal,
                    off(st.ideal, st.truth).c_str(), st.samples,
                    static_cast<double>(st.samples) / hz);
    }
    s += line;
  };
  row("soft layer", d.soft);
  row("nodule", d.hard);
  if (d.soft.reached || d.hard.reached)
    s += "  (a perfect estimate: the true distal torque rendered against the master angle, what "
         "an exact estimate would feel like. It falls below the truth where the slave's joint "
         "lags the master under load (tendon stretch, tracking error: the hand travels further "
         "than the tool). A felt value nearer the truth than it is not a better estimate: an "
         "error of the estimate, e.g. torque overshoot while pressing, offsets that lag.)\n";
  return s;
}

std::string format_report(const EvaluationReport& r) {
  std::string s;
  char line[512];
  // The loop's timing is in haptic-server's own exit summary (printed once).
  for (const auto& j : r.joints) {
    std::snprintf(line, sizeof line,
                  "joint %-8s distal torque rmse against the truth: estimated %.4f N m, naive "
                  "(tau_in) %.4f N m, estimated / naive %.2f (%zu ticks, true peak %.3f N m)\n",
                  j.name.c_str(), j.rmse_estimated, j.rmse_naive, j.ratio, j.samples, j.true_peak);
    s += line;
    if (j.free_samples) {
      std::snprintf(line, sizeof line,
                    "      %-8s free motion (|true| < %.3f N m, %zu ticks): phantom torque on "
                    "the master %.4f N m rms, naive %.4f N m rms, rendered / naive %.2f\n",
                    "", kPhantomThreshold, j.free_samples, j.phantom_rendered, j.phantom_naive,
                    j.phantom_ratio);
      s += line;
      std::snprintf(
          line, sizeof line,
          "      %-8s free motion: distal torque rmse estimated %.4f N m, naive %.4f N m\n", "",
          j.free_rmse_estimated, j.free_rmse_naive);
      s += line;
    }
    if (j.contact_samples) {
      std::snprintf(line, sizeof line,
                    "      %-8s in contact (%zu ticks): distal torque rmse estimated %.4f N m, "
                    "naive %.4f N m, estimated / naive %.2f\n",
                    "", j.contact_samples, j.contact_rmse_estimated, j.contact_rmse_naive,
                    j.contact_ratio);
      s += line;
    }
  }
  const auto& d = r.discrimination;
  if (d.joint >= 0) {
    s += format_stiffness(d, r.nominal_rate_hz);
  } else {
    s += "stiffness felt: no tissue contact in this run\n";
  }
  return s;
}

}  // namespace tsmh::haptics
