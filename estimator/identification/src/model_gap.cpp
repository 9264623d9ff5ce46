#include "estimator/model_gap.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <map>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "estimator/fit_workflow.hpp"
#include "estimator/separable_fit.hpp"
#include "estimator/simulate.hpp"
#include "number_text.hpp"
#include "realtime/enum_names.hpp"
#include "realtime/quantile.hpp"

namespace tsmh::estimator {
namespace {

using Clock = std::chrono::steady_clock;

std::string pct(double fraction) {
  return num(100.0 * fraction, 3) + " %";
}

std::string qualified(TermKind kind, std::size_t param) {
  const auto& info = term_info(kind);
  return std::string(info.name) + "." + std::string(info.params[param].name);
}

// The parameters whose value scales a term's contribution (its regressors);
// the other parameters are shapes kept at their catalog defaults until the refit.
std::vector<std::size_t> amplitude_params(TermKind kind) {
  switch (kind) {
    case TermKind::kPositionDependent:
      return {0, 1};
    case TermKind::kTimeVarying:
      return {0, 1};  // drift, step (at the scanned step time)
    case TermKind::kPositionRipple:
      return {0, 1};  // sine and cosine amplitudes (at the scanned wavenumber)
    case TermKind::kAccelerationDependence:
      return {0, 2};  // mu2, mu3
    case TermKind::kLoadScaling:
      return {0, 1, 2};  // k_abs, k_signed, k_along
    default:
      return {0};
  }
}

double coulomb_level(const TsmModelSpec& s) {
  for (const auto& t : s.terms) {
    if (t.kind == TermKind::kCoulomb) return t.p[0];
  }
  return 0.0;
}

// Adds `kind` with no effect yet: amplitudes 0 (rho2 = rho1, so the negative
// branch keeps its level), shapes at their defaults, the drift's time origin
// at the start of the record and the step after its end.
double mean_tension(const FitData& d) {
  double sum = 0.0, n = 0.0;
  for (const auto& m : d.motion)
    if (std::isfinite(m.tension)) sum += m.tension, n += 1.0;
  return n > 0.0 ? sum / n : 0.0;
}

// Whether the data carries what a candidate reads: the multiplicative forms
// need the drive (distal load) or the tendon tensions.
bool data_has_variable(const FitData& d, TermKind kind) {
  const auto any = [&](auto get) {
    return std::any_of(d.motion.begin(), d.motion.end(),
                       [&](const Motion& m) { return std::isfinite(get(m)); });
  };
  if (kind == TermKind::kLoadScaling) return any([](const Motion& m) { return m.drive; });
  if (kind == TermKind::kTensionScaling) return any([](const Motion& m) { return m.tension; });
  return true;
}

// Whether a candidate is tried on this data. The forms on |tau_in| / R
// (load_dependent, load_saturating) only where the distal load is unknown,
// or when asked for by name: |tau_in| / R contains the friction itself (in
// free motion it is the friction), so they imitate any effect that makes
// the friction larger, viscous drag first; load_scaling reads the distal
// load instead.
bool offered(const FitData& d, TermKind kind, const GapOptions& o) {
  if (!data_has_variable(d, kind)) return false;
  // A scaling whose quantity does not vary in the data cannot be told from
  // a level (the same gate as the distributed slip's copies).
  const CopiesInData varies = copies_in_data(d);
  if (kind == TermKind::kLoadScaling && !varies.load) return false;
  if (kind == TermKind::kTensionScaling && !varies.tension) return false;
  const bool on_tau_in = kind == TermKind::kLoadDependent || kind == TermKind::kLoadSaturating;
  if (!on_tau_in || data_has_variable(d, TermKind::kLoadScaling) == false) return true;
  return std::any_of(o.candidates.begin(), o.candidates.end(),
                     [&](const std::string& c) { return c == term_info(kind).name; });
}

TsmModelSpec with_neutral_term(TsmModelSpec spec, TermKind kind, const FitData& d) {
  const double t_start = d.motion.front().t, t_end = d.motion.back().t;
  const double rho1 = coulomb_level(spec);
  Term& t = spec.add(kind);
  for (std::size_t k : amplitude_params(kind))
    t.p[k] = 0.0;
  if (kind == TermKind::kDirectionAsymmetry) t.p[0] = std::max(rho1, 0.01);
  if (kind == TermKind::kTimeVarying) {
    t.p[2] = t_end + 1.0;  // t_step: no step inside the record
    t.p[3] = t_start;      // t0
  }
  if (kind == TermKind::kTensionScaling) t.p[1] = mean_tension(d);  // t_ref
  return spec;
}

std::size_t index_of(const std::vector<Parameter>& params, const std::string& name) {
  for (std::size_t i = 0; i < params.size(); ++i) {
    if (params[i].name == name) return i;
  }
  throw std::logic_error("model_gap: no parameter " + name);
}

std::vector<double> values_of(const FrictionModel& m) {
  std::vector<double> v;
  for (const auto& p : m.parameters())
    v.push_back(p.value);
  return v;
}

// dF/dp of parameter `i`, by a forward step of 1e-3 of its range (backward
// at the upper bound).
std::vector<double> sensitivity(const TsmFrictionModel& model, std::size_t i,
                                std::span<const Motion> motion, std::span<const double> f0) {
  const auto params = model.parameters();
  std::vector<double> v = values_of(model);
  double h = 1e-3 * (params[i].upper - params[i].lower);
  if (v[i] + h > params[i].upper) h = -h;
  v[i] += h;
  TsmFrictionModel m = model;
  m.set_values(v);
  std::vector<double> g = simulate_friction(m, motion);
  for (std::size_t k = 0; k < g.size(); ++k)
    g[k] = (g[k] - f0[k]) / h;
  return g;
}

struct Projection {
  double explained = 0.0;    // 1 - |r - G b|^2 / |r|^2
  std::vector<double> beta;  // least-squares coefficients
};

// Least squares of the residual on the regressors, over the train samples.
Projection project(const FitData& d, std::span<const double> residual,
                   const std::vector<std::vector<double>>& regressors) {
  Projection p;
  const auto m = static_cast<Eigen::Index>(regressors.size());
  p.beta.assign(regressors.size(), 0.0);
  if (m == 0) return p;
  Eigen::MatrixXd gtg = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd gtr = Eigen::VectorXd::Zero(m);
  double rr = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d.role[i] != SampleRole::kTrain) continue;
    rr += residual[i] * residual[i];
    for (Eigen::Index a = 0; a < m; ++a) {
      const double ga = regressors[static_cast<std::size_t>(a)][i];
      gtr(a) += ga * residual[i];
      for (Eigen::Index b = 0; b < m; ++b)
        gtg(a, b) += ga * regressors[static_cast<std::size_t>(b)][i];
    }
  }
  if (!(rr > 0.0)) return p;
  const Eigen::VectorXd beta = gtg.completeOrthogonalDecomposition().solve(gtr);
  // |r - G b|^2 = |r|^2 - b^T G^T r for the least-squares b.
  p.explained = std::clamp(beta.dot(gtr) / rr, 0.0, 1.0);
  for (Eigen::Index a = 0; a < m; ++a)
    p.beta[static_cast<std::size_t>(a)] = std::isfinite(beta(a)) ? beta(a) : 0.0;
  return p;
}

// One way to start a candidate's refit: the spec with the term seeded by the
// first-order estimate, further starting points, narrower bounds.
struct Variant {
  TsmModelSpec seeded;
  std::vector<std::vector<double>> extra_starts;  // e.g. the neutral term
  std::vector<BoundsOverride> bounds;
};

// A candidate prepared for its refit. time_varying has one variant per
// promising step time (a step time is a discrete choice a local optimiser
// cannot move far), each searched within +-5 % of the record around it.
struct Prepared {
  TermKind kind;
  double explained = 0.0;
  std::vector<Variant> variants;
};

// Seeds `neutral` with the least-squares coefficients of `regs` on the
// residual; returns the seeded values.
std::vector<double> seed_values(const TsmFrictionModel& neutral,
                                const std::vector<std::size_t>& amp, const Projection& proj) {
  std::vector<double> v = values_of(neutral);
  const auto sp = neutral.parameters();
  for (std::size_t a = 0; a < amp.size(); ++a)
    v[amp[a]] = std::clamp(v[amp[a]] + proj.beta[a], sp[amp[a]].lower, sp[amp[a]].upper);
  return v;
}

// A setting of a candidate's shape parameters (a step time, a wavenumber, a
// bump's place and width) to scan by first-order projection: shapes are
// choices a local optimiser cannot move far, so the refit starts from the
// best few, each searched within bounds around it.
struct Shape {
  std::vector<std::pair<std::size_t, double>> set;  // parameter index within the term, value
  std::vector<BoundsOverride> bounds;
  double key = 0.0;  // for keeping chosen shapes apart
};

std::vector<Shape> shapes_to_scan(const FitData& d, TermKind kind, double& min_separation) {
  std::vector<Shape> out;
  const double t0 = d.motion.front().t, t1 = d.motion.back().t;
  double xmin = d.motion.front().x, xmax = xmin;
  std::vector<double> load;
  for (const auto& m : d.motion) {
    xmin = std::min(xmin, m.x);
    xmax = std::max(xmax, m.x);
    load.push_back(m.load);
  }
  const double span = std::max(xmax - xmin, 1e-3);
  const auto q = [](const std::vector<double>& v, double f) { return realtime::quantile(v, f); };
  switch (kind) {
    case TermKind::kTimeVarying: {
      // Step time over the record (5 %..95 %), each searched within +-5 %.
      min_separation = 0.1 * (t1 - t0);
      const double half = 0.05 * (t1 - t0);
      for (int k = 0; k <= 36; ++k) {
        const double ts = t0 + (0.05 + 0.9 * k / 36.0) * (t1 - t0);
        out.push_back({{{2, ts}}, {{qualified(kind, 2), ts - half, ts + half}}, ts});
      }
      break;
    }
    case TermKind::kPositionRipple: {
      // Periods over the stroke, each searched within +-15 %.
      min_separation = 1.5 * 2.0 * std::numbers::pi / span;
      // 1 to 12 periods, then up to 40 by twos: a short-period ripple (a
      // sheath's winding, a gear's teeth) is as plausible as a long one.
      for (int j = 1; j <= 40; j += j < 12 ? 1 : 2) {
        const double k = 2.0 * std::numbers::pi * j / span;
        out.push_back({{{2, k}}, {{qualified(kind, 2), 0.85 * k, 1.15 * k}}, k});
      }
      break;
    }
    case TermKind::kPositionBump: {
      // 12 places along the stroke, two widths; each place searched within
      // +-1/8 of the stroke.
      min_separation = span / 6.0;
      for (int i = 0; i < 12; ++i) {
        const double c = xmin + (i + 0.5) / 12.0 * span;
        for (double w : {span / 25.0, span / 10.0}) {
          out.push_back({{{1, c}, {2, w}},
                         {{qualified(kind, 1), c - span / 8.0, c + span / 8.0},
                          {qualified(kind, 2), span / 100.0, span / 2.0}},
                         c});
        }
      }
      break;
    }
    case TermKind::kLoadSaturating: {
      min_separation = 0.0;
      for (double f : {0.5, 0.9}) {
        const double l = std::max(q(load, f), 0.2);
        out.push_back({{{1, l}}, {}, l});
      }
      break;
    }
    default:
      break;
  }
  return out;
}

Prepared prepare_candidate(const FitData& d, const TsmFrictionModel& current,
                           std::span<const double> f_cur, std::span<const double> residual,
                           TermKind kind) {
  Prepared p{kind, 0.0, {}};
  const TsmFrictionModel neutral(with_neutral_term(current.spec(), kind, d));
  const auto params = neutral.parameters();
  std::vector<std::size_t> amp;
  for (std::size_t k : amplitude_params(kind))
    amp.push_back(index_of(params, qualified(kind, k)));

  double min_separation = 0.0;
  const std::vector<Shape> shapes = shapes_to_scan(d, kind, min_separation);
  if (shapes.empty()) {
    std::vector<std::vector<double>> regs;
    for (std::size_t i : amp)
      regs.push_back(sensitivity(neutral, i, d.motion, f_cur));
    const Projection proj = project(d, residual, regs);
    p.explained = proj.explained;
    TsmFrictionModel seeded = neutral;
    seeded.set_values(seed_values(neutral, amp, proj));
    p.variants.push_back({seeded.spec(), {values_of(neutral)}, {}});
    return p;
  }

  const auto with_shape = [&](const Shape& sh) {
    std::vector<double> v = values_of(neutral);
    for (const auto& [k, value] : sh.set)
      v[index_of(params, qualified(kind, k))] = value;
    TsmFrictionModel m = neutral;
    m.set_values(v);
    return m;
  };
  // time_varying's drift does not depend on the step time: one regressor.
  std::vector<double> drift;
  if (kind == TermKind::kTimeVarying) drift = sensitivity(neutral, amp[0], d.motion, f_cur);
  std::vector<std::pair<double, std::size_t>> scan;  // explained, shape
  std::vector<Projection> projections;
  for (std::size_t s = 0; s < shapes.size(); ++s) {
    const TsmFrictionModel m = with_shape(shapes[s]);
    std::vector<std::vector<double>> regs;
    for (std::size_t a = 0; a < amp.size(); ++a) {
      if (kind == TermKind::kTimeVarying && a == 0)
        regs.push_back(drift);
      else
        regs.push_back(sensitivity(m, amp[a], d.motion, f_cur));
    }
    projections.push_back(project(d, residual, regs));
    scan.push_back({projections.back().explained, s});
  }
  std::stable_sort(scan.begin(), scan.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<std::size_t> chosen;
  // The scans pick the right shape reliably; time keeps two step times
  // (a step and a drift look alike to first order).
  const std::size_t keep = kind == TermKind::kTimeVarying ? 2 : 1;
  for (const auto& [e, s] : scan) {
    const bool apart = std::all_of(chosen.begin(), chosen.end(), [&](std::size_t c) {
      return std::fabs(shapes[c].key - shapes[s].key) > min_separation;
    });
    if (apart && chosen.size() < keep) chosen.push_back(s);
  }
  p.explained = scan.front().first;
  for (std::size_t s : chosen) {
    const TsmFrictionModel m = with_shape(shapes[s]);
    TsmFrictionModel seeded = m;
    seeded.set_values(seed_values(m, amp, projections[s]));
    p.variants.push_back({seeded.spec(), {values_of(m)}, shapes[s].bounds});
  }
  return p;
}

double bic(double mse, double n_eff, std::size_t k) {
  return n_eff * std::log(mse) + static_cast<double>(k) * std::log(n_eff);
}

std::size_t free_count(const FrictionModel& m) {
  std::size_t k = 0;
  for (const auto& p : m.parameters())
    k += p.fixed ? 0 : 1;
  return k;
}

std::vector<TermKind> candidate_kinds(const GapOptions& o) {
  std::vector<TermKind> out;
  if (o.candidates.empty()) {
    for (const auto& info : term_catalog()) {
      if (info.kind != TermKind::kCoulomb) out.push_back(info.kind);
    }
    return out;
  }
  for (const auto& name : o.candidates) {
    // A family name (position_dependent, load_dependent) brings all its forms.
    // The structural candidates are chosen in each round (structural_candidates).
    bool found = name == "distributed_slip" || name == "load_copies" || name == "tension_copies" ||
                 name == "tendon_widths" || name == "distal_slip";
    for (const auto& info : term_catalog()) {
      if (info.name == name || term_family(info.kind) == name) {
        if (std::find(out.begin(), out.end(), info.kind) == out.end()) out.push_back(info.kind);
        found = true;
      }
    }
    if (!found) throw std::invalid_argument("unknown candidate effect '" + name + "'");
  }
  return out;
}

// The experiment that tells two effects apart: vary one's variable while
// the other's stays the same.
std::string separating_experiment(const std::string& a, const std::string& b) {
  const auto pair = [&](const char* x, const char* y) {
    return (a == x && b == y) || (a == y && b == x);
  };
  if (pair("load_dependent", "position_dependent"))
    return "contact at several positions (press the tissue at different angles), or free motion "
           "plus contact in one recording, so the same angles occur with different loads";
  if (pair("load_dependent", "time_varying"))
    return "the same loads early and late in the recording (alternate contact and free motion)";
  if (pair("position_dependent", "time_varying"))
    return "the whole stroke covered early and late in the recording";
  if (pair("viscous", "load_dependent"))
    return "the same speeds at several loads (free motion and contact at each speed)";
  if (pair("viscous", "position_dependent"))
    return "fast and slow motion over the same part of the stroke";
  if (pair("viscous", "time_varying")) return "the same speeds early and late in the recording";
  if (pair("load_dependent", "tension_dependent"))
    return "the same tip loads at two pretensions (retension the tendons between two runs)";
  if (pair("distributed_slip", "hysteresis_elements"))
    return "reversals of many sizes, from a few mrad to the whole stroke";
  return "a recording in which the variables of " + a + " and " + b + " vary independently";
}

// The variable a family's added term is plotted against.
const char* variable_of(std::string_view family) {
  if (family == "position_dependent") return "x";
  if (family == "load_dependent") return "load";
  if (family == "time_varying") return "t";
  if (family == "tension_dependent") return "tension";
  return "speed";
}

std::vector<double> residual_of(const FitData& d, std::span<const double> f) {
  std::vector<double> r(d.size());
  for (std::size_t i = 0; i < d.size(); ++i)
    r[i] = d.measured[i] - f[i];
  return r;
}

// The regime group where a term's absence shows (fit_metrics.hpp groups).
std::string group_of(TermKind kind) {
  switch (kind) {
    case TermKind::kViscous:
    case TermKind::kStribeck:
      return "speed";
    case TermKind::kLoadDependent:
    case TermKind::kLoadScaling:
    case TermKind::kLoadSaturating:
    case TermKind::kTensionScaling:
      return "load";
    case TermKind::kPositionDependent:
    case TermKind::kPositionRipple:
    case TermKind::kPositionBump:
      return "position";
    case TermKind::kTimeVarying:
      return "time";
    case TermKind::kAccelerationDependence:
      return "acceleration";
    default:
      return "direction";
  }
}

// What the base got wrong in the term's own regimes: the friction magnitude
// measured minus modelled, per regime of its group.
std::string own_regimes(TermKind kind, const std::vector<RegimeError>& before) {
  std::string text;
  for (const auto& r : before) {
    if (r.group != group_of(kind) || !std::isfinite(r.magnitude_excess)) continue;
    text += (text.empty() ? "" : ", ") + r.name + " " + (r.magnitude_excess >= 0 ? "+" : "") +
            num(r.magnitude_excess) + " N";
  }
  return text.empty() ? "" : "measured minus model friction magnitude: " + text;
}

// Where the residual fell most between two regime breakdowns.
std::string where_it_fell(const std::vector<RegimeError>& before,
                          const std::vector<RegimeError>& after) {
  double best = 0.0;
  std::string text;
  for (std::size_t i = 0; i < before.size() && i < after.size(); ++i) {
    const double drop = before[i].metrics.rmse - after[i].metrics.rmse;
    if (before[i].metrics.samples > 0 && drop > best) {
      best = drop;
      text = before[i].name + " (" + before[i].where + "): RMSE " + num(before[i].metrics.rmse) +
             " -> " + num(after[i].metrics.rmse) + " N";
    }
  }
  return text;
}

CandidateTrial score_trial(const FitData& d, std::span<const double> f_cur,
                           const ErrorMetrics& gap_cur, double noise, const FitResult& fit,
                           const GapOptions& o);

// Refits a prepared candidate locally: each variant (the current model with
// the term added at one scanned shape); the best train fit counts. Scores the
// validation gap against `gap_cur`: the relative gain, and the significance
// of the drop in squared error (z over the correlation time; the share of the
// MSE above the noise floor it removes). BIC is left to the caller.
CandidateTrial refit_candidate(const FitData& d, std::span<const double> f_cur,
                               const ErrorMetrics& gap_cur, double noise, const Prepared& p,
                               const GapOptions& o, std::uint64_t seed) {
  std::optional<FitResult> best;
  long evaluations = 0;
  for (std::size_t v = 0; v < p.variants.size(); ++v) {
    const Variant& var = p.variants[v];
    FitOptions fo;
    fo.seed = seed + 7 * v;
    fo.global_stage = false;
    fo.threads = 1;
    // LM: every start (seeded, neutral) is screened on the decimated data;
    // the better one is polished on the full-rate data.
    fo.starts = o.base_fit.method == "lm" ? 1 : 1 + static_cast<int>(var.extra_starts.size());
    fo.method = o.base_fit.method;
    fo.polish_iterations = o.refit_polish_iterations;
    fo.extra_starts = var.extra_starts;
    fo.bounds = var.bounds;
    fo.coarse_local_evaluations = o.refit_coarse_evaluations;
    fo.local_evaluations = o.refit_evaluations;
    fo.slip_copies_from_data = false;
    FitResult r = identify(TsmFrictionModel(var.seeded), d, fo);
    evaluations += r.evaluations;
    if (!best || r.train_rmse < best->train_rmse) best = std::move(r);
  }
  CandidateTrial t = score_trial(d, f_cur, gap_cur, noise, *best, o);
  t.name = std::string(term_info(p.kind).name);
  t.family = std::string(term_family(p.kind));
  t.explained = p.explained;
  t.evaluations = evaluations;
  return t;
}

// The validation gain of a refitted candidate against `gap_cur`: the
// relative gain, and the significance of the drop in squared error (z over
// the correlation time; the share of the MSE above the noise floor it
// removes). BIC is left to the caller.
CandidateTrial score_trial(const FitData& d, std::span<const double> f_cur,
                           const ErrorMetrics& gap_cur, double noise, const FitResult& fit,
                           const GapOptions& o) {
  CandidateTrial t;
  t.validation = error_metrics(d, fit.simulated, SampleRole::kValidation);
  t.train_mse = fit.train_rmse * fit.train_rmse;
  t.free_parameters = free_count(*fit.model);
  t.gain = 1.0 - t.validation.rmse / gap_cur.rmse;
  std::vector<double> drop;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d.role[i] != SampleRole::kValidation) continue;
    const double eb = d.measured[i] - f_cur[i], ea = d.measured[i] - fit.simulated[i];
    drop.push_back(eb * eb - ea * ea);
  }
  double mean = 0.0, var = 0.0;
  for (double v : drop)
    mean += v;
  mean /= static_cast<double>(drop.size());
  for (double v : drop)
    var += (v - mean) * (v - mean);
  var /= static_cast<double>(drop.size());
  const double se = std::sqrt(var * correlation_time(drop) / static_cast<double>(drop.size()));
  t.z = se > 0.0 ? mean / se : 0.0;
  const double excess = gap_cur.rmse * gap_cur.rmse - noise * noise;
  t.excess_share = excess > 0.0 ? mean / excess : 0.0;
  t.qualifies = t.gain > 0.0 &&
                (t.gain >= o.margin || (t.z >= o.min_z && t.excess_share >= o.min_excess_share));
  t.values = fit.values;
  t.fitted = dynamic_cast<const TsmFrictionModel&>(*fit.model).spec();
  return t;
}

// Structural candidates: effects that change the model's structure rather
// than add a level term. distributed_slip adds a family of elasto-slide
// elements (distributed_slip.hpp) beside the current hysteresis; on a model
// with distributed slip, the load and tension dependences are its copies:
// every basis function scaled by the distal load or the tendons' tension
// (per element multiplicative, the capstan form), identified exactly.
// A sheath's slip and its tension dependence come together: the break force
// of every stuck segment is mu times its local tension, so on a sheath whose
// tension changes a lot (a large wrap, tip loads) the elements alone explain
// little and the copies alone have nothing to scale. Distributed slip is
// therefore also tried with its tension copies at once (the break force
// follows the tension; a tip load acts on it through the tendons'
// tensions); when the pair wins, both effects are named, with what the
// elements alone gave. The load copies come after, on a model with slip.
// Where both proximal tensions are recorded, the tension dependence also
// comes as per-tendon element families (`tendon_widths`, with the copies):
// each sheath's presliding widths and break forces scale with its own
// tendon's tension, friction x g(T_j), g_j = max(T_j, 0) / T_ref, so a slack
// tendon's sheath carries none; the copies scale only the break forces.
enum class Structural {
  kDistributedSlip,
  kSlipWithTension,
  kSlipWithWidths,
  kLoadCopies,
  kTensionCopies,
  kTendonWidths,
  kDistalSlip
};

const char* structural_name(Structural s) {
  return realtime::enum_name<Structural::kDistalSlip>(
             s, {"distributed_slip", "distributed_slip+tension_copies",
                 "distributed_slip+tendon_widths", "load_copies", "tension_copies", "tendon_widths",
                 "distal_slip"})
      .data();
}

// The copies a pair adds (the distributed slip itself: none).
std::optional<Structural> copies_of(Structural s) {
  if (s == Structural::kSlipWithTension) return Structural::kTensionCopies;
  if (s == Structural::kSlipWithWidths) return Structural::kTendonWidths;
  return std::nullopt;
}

// A pair's family is its copies' (the effect it adds beyond the elements),
// so that it meets the load and tension level terms as a rival.
const char* structural_family(Structural s) {
  return realtime::enum_name<Structural::kDistalSlip>(
             s, {"distributed_slip", "tension_dependent", "tension_dependent", "load_dependent",
                 "tension_dependent", "tension_dependent", "distal_slip"})
      .data();
}

// Whether a candidate makes the elements per-tendon families.
bool adds_widths(Structural s) {
  return s == Structural::kSlipWithWidths || s == Structural::kTendonWidths;
}

std::optional<Structural> structural_from_name(const std::string& name) {
  for (Structural s :
       {Structural::kDistributedSlip, Structural::kSlipWithTension, Structural::kSlipWithWidths,
        Structural::kLoadCopies, Structural::kTensionCopies, Structural::kTendonWidths,
        Structural::kDistalSlip})
    if (name == structural_name(s)) return s;
  return std::nullopt;
}

// Whether a trial adds distributed slip (alone or with copies).
bool adds_slip(const std::string& name) {
  return name.rfind("distributed_slip", 0) == 0;
}

// The families the model already has, level terms and structure.
bool family_present(const TsmModelSpec& spec, std::string_view family) {
  if (family == "distributed_slip" && spec.slip.enabled) return true;
  if (family == "distal_slip" && spec.slip.enabled && spec.slip.distal_elements > 0) return true;
  if (family == "load_dependent" && spec.slip.enabled && spec.slip.load_copies) return true;
  if (family == "tension_dependent" && spec.slip.enabled &&
      (spec.slip.tension_copies || spec.slip.tendon_widths))
    return true;
  return std::any_of(spec.terms.begin(), spec.terms.end(),
                     [&](const Term& t) { return term_family(t.kind) == family; });
}

// The structural candidates the current model and the data allow.
std::vector<Structural> structural_candidates(const TsmModelSpec& spec, const FitData& d,
                                              const GapOptions& o) {
  const auto named = [&](Structural s) {
    return std::any_of(o.candidates.begin(), o.candidates.end(), [&](const std::string& c) {
      return c == structural_name(s) || c == structural_family(s);
    });
  };
  const auto wanted = [&](Structural s) {
    if (o.candidates.empty()) return true;
    if (const auto c = copies_of(s)) return named(Structural::kDistributedSlip) && named(*c);
    return named(s);
  };
  std::vector<Structural> out;
  const CopiesInData copies = copies_in_data(d);
  // The per-tendon families need T1 and T3 on every sample.
  const bool widths = tensions_measured(d) && !family_present(spec, "tension_dependent");
  if (!spec.slip.enabled) {
    if (wanted(Structural::kDistributedSlip)) out.push_back(Structural::kDistributedSlip);
    if (copies.tension && !family_present(spec, "tension_dependent") &&
        wanted(Structural::kSlipWithTension))
      out.push_back(Structural::kSlipWithTension);
    if (widths && wanted(Structural::kSlipWithWidths)) out.push_back(Structural::kSlipWithWidths);
    return out;
  }
  if (copies.load && !family_present(spec, "load_dependent") && wanted(Structural::kLoadCopies))
    out.push_back(Structural::kLoadCopies);
  if (copies.tension && !family_present(spec, "tension_dependent") &&
      wanted(Structural::kTensionCopies))
    out.push_back(Structural::kTensionCopies);
  if (widths && !spec.slip.tendon_widths && wanted(Structural::kTendonWidths))
    out.push_back(Structural::kTendonWidths);
  // Slip driven from the tip needs the distal angle on every sample.
  if (distal_angle_measured(d) && spec.slip.distal_elements == 0 && wanted(Structural::kDistalSlip))
    out.push_back(Structural::kDistalSlip);
  return out;
}

// The structural candidate added to `current` and identified: the linear
// block exactly, the elements' spread by grid and BOBYQA, their number by
// BIC (separable_fit.hpp); the current model's own parameters from where
// they are. A pair on a model that already has distributed slip adds only
// its copies. With `may_replace` (no effect named yet: the model is the
// base) distributed slip is also tried instead of the base's hysteresis,
// the elements and their sliding functions alone: the base's Bouc-Wen state
// fitted to a sheath whose slip spreads is a compromise the elements can
// only add to (their break forces are not negative), and the search moves
// its parameters only locally. The better train fit of the two counts.
CandidateTrial refit_structural(const FitData& d, const TsmFrictionModel& current,
                                std::span<const double> f_cur, const ErrorMetrics& gap_cur,
                                double noise, Structural which, const GapOptions& o,
                                std::uint64_t seed, bool may_replace = false) {
  TsmModelSpec spec = current.spec();
  FitOptions fo = o.base_fit;
  fo.progress = nullptr;
  fo.seed = seed;
  fo.threads = 1;
  fo.slip_copies_from_data = false;
  fo.global_stage = false;
  const bool adds_elements =
      which == Structural::kDistributedSlip || (copies_of(which) && !spec.slip.enabled);
  if (adds_elements) {
    spec.slip = default_distributed_slip();
    fo.global_stage = true;  // the spread and the element count are searched
  }
  if (adds_widths(which)) {
    // One family per tendon, at the count tsm fit tries (each family spans
    // the same widths at the reference tension); their spread is searched.
    spec.slip.tendon_widths = true;
    spec.slip.elements = adds_elements ? 8 : std::min(spec.slip.elements, 12);
    spec.slip.tension_ref = std::round(mean_tension(d) * 10.0) / 10.0;
    fo.global_stage = true;
  }
  if (which == Structural::kLoadCopies) {
    spec.slip.load_copies = true;
    spec.slip.load_weight = {};
  }
  // Each tendon's own tension, T1 = T + u/2 and T3 = T - u/2 (T the mean,
  // u = tau_in / R): the mean tension's copies and, where the drive varies
  // apart from the friction (tip loads), the drive's, so that each sheath's
  // friction scales with its own tendon (distributed_slip.hpp).
  const bool tension_copies = which == Structural::kTensionCopies ||
                              which == Structural::kSlipWithTension ||
                              (adds_widths(which) && copies_in_data(d).tension);
  if (tension_copies) {
    spec.slip.tension_copies = true;
    spec.slip.tension_weight = {};
    spec.slip.tension_ref = std::round(mean_tension(d) * 10.0) / 10.0;
    if (copies_in_data(d).drive) {
      spec.slip.drive_copies = true;
      spec.slip.drive_weight = {};
    }
  }
  long distal_solves = 0;
  if (which == Structural::kDistalSlip) {
    // The family's position along the sheath: the one of tsm fit's few
    // whose weights, solved exactly over the current spread, fit best.
    double best = std::numeric_limits<double>::infinity();
    TsmModelSpec chosen = spec;
    for (double a : kDistalPositions) {
      TsmModelSpec c = spec;
      c.slip.distal_elements = kDistalCandidateElements;
      c.slip.distal_position = a;
      const double mse = solve_slip_weights(c, d, 4);
      ++distal_solves;
      if (mse < best) best = mse, chosen = c;
    }
    spec = chosen;
  }
  FitResult fit = identify(TsmFrictionModel(spec), d, fo);
  long evaluations = fit.evaluations + distal_solves;
  bool replaced = false;
  if (adds_elements && may_replace && !spec.terms.empty()) {
    TsmModelSpec alone = spec;
    alone.terms.clear();
    FitResult r = identify(TsmFrictionModel(alone), d, fo);
    evaluations += r.evaluations;
    if (r.train_rmse < fit.train_rmse) fit = std::move(r), replaced = true;
  }
  CandidateTrial t = score_trial(d, f_cur, gap_cur, noise, fit, o);
  t.name = structural_name(which);
  t.family = structural_family(which);
  t.evaluations = evaluations;
  t.replaces_hysteresis = replaced;
  return t;
}

// The workflow's steps, in the order find_model_gaps() runs them.

struct Say {
  const GapOptions& o;
  void operator()(const std::string& s) const {
    if (o.progress) o.progress(s);
  }
};

// The model as the rounds have grown it, its simulation and its gap.
struct GapState {
  std::unique_ptr<TsmFrictionModel> model;
  std::vector<double> f;
  ErrorMetrics gap;
  std::vector<RegimeError> regimes;
};

void fit_base(GapResult& g, const FrictionModel& base, const GapOptions& o, const Say& say) {
  auto start = base.clone();
  adapt_scale_to_data(*start, g.data);
  FitOptions bo = o.base_fit;
  bo.slip_copies_from_data = false;  // the copies are effects the rounds name
  if (!bo.progress) {
    bo.progress = [&](const FitProgress& p) {
      say("base fit: " + std::string(p.stage) + ", " + std::to_string(p.evaluations) +
          " model runs, " + num(p.elapsed_s, 2) + " s");
    };
  }
  FitResult base_fit = identify(*start, g.data, bo);
  g.evaluations += base_fit.evaluations;
  g.base_model = base_fit.model->clone();
  g.base_simulated = base_fit.simulated;
  g.gap_base = error_metrics(g.data, g.base_simulated, SampleRole::kValidation);
  g.regimes_base = regime_errors(g.data, g.base_simulated, SampleRole::kValidation);
}

// Why no further round runs ("" to run one); `todo` gets the candidates not
// yet in the model.
std::string stop_before_round(const GapResult& g, const GapState& cur,
                              const std::vector<TermKind>& kinds, const GapOptions& o,
                              std::vector<TermKind>& todo, std::vector<Structural>& structural) {
  if (static_cast<int>(g.effects.size()) >= o.max_effects)
    return "reached the maximum of " + std::to_string(o.max_effects) + " effects";
  if (cur.gap.rmse <= o.noise_stop * g.noise)
    return "the gap (" + num(cur.gap.rmse) + " N) is at the measurement-noise floor (" +
           num(g.noise) + " N)";
  const TsmModelSpec& spec = cur.model->spec();
  for (TermKind k : kinds) {
    // Level terms need a Bouc-Wen part to add to.
    if (!spec.terms.empty() && !spec.has(k) && !family_present(spec, term_family(k)) &&
        offered(g.data, k, o))
      todo.push_back(k);
  }
  structural = structural_candidates(spec, g.data, o);
  if (todo.empty() && structural.empty()) return "every candidate is already in the model";
  return {};
}

// Every candidate in `todo` added to the current model and refitted, on a
// pool of worker threads; the trials sorted best gain first (ties to catalog
// order, so the choice is deterministic).
void run_trials(GapResult& g, const GapState& cur, const std::vector<TermKind>& todo,
                const std::vector<Structural>& structural, const GapOptions& o, const Say& say,
                Clock::time_point t_start, GapRound& round) {
  const FitData& d = g.data;
  const auto residual = residual_of(d, cur.f);
  const auto train_w = d.weights(SampleRole::kTrain);
  const double mse_cur = weighted_mse(d.measured, cur.f, train_w);
  // Effective sample size for BIC: the residual is correlated in time.
  std::vector<double> train_resid;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d.role[i] == SampleRole::kTrain) train_resid.push_back(residual[i]);
  }
  const double n_eff =
      static_cast<double>(d.count(SampleRole::kTrain)) / correlation_time(train_resid);
  const double bic_cur = bic(mse_cur, n_eff, free_count(*cur.model));

  // The structural candidates first: distributed slip's refit is the
  // longest, so the pool starts it first.
  const std::size_t total = structural.size() + todo.size();
  round.trials.resize(total);
  std::vector<std::exception_ptr> errors(total);
  std::atomic<std::size_t> next{0};
  std::atomic<std::size_t> done{0};
  const auto work = [&] {
    for (std::size_t ci = next.fetch_add(1); ci < total; ci = next.fetch_add(1)) {
      if (ci < structural.size()) {
        try {
          CandidateTrial& t = round.trials[ci];
          t = refit_structural(d, *cur.model, cur.f, cur.gap, g.noise, structural[ci], o,
                               o.base_fit.seed + 53 * (ci + 1), g.effects.empty());
          t.bic = bic(t.train_mse, n_eff, t.free_parameters);
          t.delta_bic = t.bic - bic_cur;
        } catch (...) {
          errors[ci] = std::current_exception();
        }
        done.fetch_add(1);
        continue;
      }
      const std::size_t c = ci - structural.size();
      try {
        const Prepared p = prepare_candidate(d, *cur.model, cur.f, residual, todo[c]);
        CandidateTrial& t = round.trials[ci];
        if (p.explained < o.min_explained) {
          // Its regressors explain next to nothing of the residual: a
          // refit cannot shrink the gap (saves most of a null round).
          t.name = std::string(term_info(todo[c]).name);
          t.family = std::string(term_family(todo[c]));
          t.explained = p.explained;
          t.validation = cur.gap;
          t.train_mse = mse_cur;
          t.skipped = true;
          t.bic = bic_cur;
        } else {
          t = refit_candidate(d, cur.f, cur.gap, g.noise, p, o, o.base_fit.seed + 101 * (c + 1));
          t.bic = bic(t.train_mse, n_eff, t.free_parameters);
          t.delta_bic = t.bic - bic_cur;
        }
      } catch (...) {
        errors[ci] = std::current_exception();
      }
      done.fetch_add(1);
    }
  };
  const int hw = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  const int threads = o.threads > 0 ? o.threads : hw;
  std::vector<std::thread> pool;
  for (int w = 0; w < std::min<int>(threads, static_cast<int>(total)); ++w)
    pool.emplace_back(work);
  while (done.load() < total) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    say("round " + std::to_string(g.rounds.size() + 1) + ": " + std::to_string(done.load()) + "/" +
        std::to_string(total) + " candidates refitted, " +
        num(std::chrono::duration<double>(Clock::now() - t_start).count(), 3) + " s");
  }
  for (auto& t : pool)
    t.join();
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
  for (const auto& t : round.trials)
    g.evaluations += t.evaluations;
  std::stable_sort(round.trials.begin(), round.trials.end(),
                   [](const auto& a, const auto& b) { return a.gain > b.gain; });
}

// Rivals: other effects that qualified nearly as well as the winner. Would
// the winner still add after the rival? If not, this data cannot tell them
// apart (decided after the last round: find_confounds).
void check_rivals(GapResult& g, const CandidateTrial& win, const GapOptions& o, const Say& say,
                  GapRound& round) {
  const FitData& d = g.data;
  const std::optional<TermKind> kind = term_kind_from_name(win.name);
  std::map<std::string, const CandidateTrial*> rivals;
  for (const auto& t : round.trials) {
    if (t.family == win.family || !t.qualifies || t.gain < o.confound_ratio * win.gain) continue;
    // Distributed slip alone and a pair with it are one model growing, not rivals.
    if (adds_slip(t.name) && adds_slip(win.name)) continue;
    if (!rivals.count(t.family) || rivals[t.family]->gain < t.gain) rivals[t.family] = &t;
  }
  for (const auto& [family, r] : rivals) {
    say("checking whether " + win.family + " still adds after " + family);
    TsmFrictionModel with_rival(r->fitted);
    const auto f_r = simulate_friction(with_rival, d.motion);
    const auto gap_r = error_metrics(d, f_r, SampleRole::kValidation);
    CandidateTrial back;
    if (kind) {
      const Prepared pw = prepare_candidate(d, with_rival, f_r, residual_of(d, f_r), *kind);
      back = refit_candidate(d, f_r, gap_r, g.noise, pw, o, o.base_fit.seed + 977);
    } else if (win.name == "distributed_slip" && with_rival.spec().slip.enabled) {
      continue;  // the rival is a copy of distributed slip: nothing to add it to
    } else if (!kind && family_present(with_rival.spec(), win.family)) {
      continue;  // the rival already has the winner's copies
    } else {
      back = refit_structural(d, with_rival, f_r, gap_r, g.noise, *structural_from_name(win.name),
                              o, o.base_fit.seed + 977);
    }
    g.evaluations += back.evaluations;
    round.rivals.push_back({family, r->gain, back.gain, back.qualifies});
  }
}

// The candidate's refit polished only briefly on the full-rate data; this
// converges the augmented model (warm Levenberg-Marquardt from the refit:
// the base was already global). Kept when it fits the train data better
// (validation is not used to choose). Time parameters (a step time) stay
// where the scan and the refit put them: inside a validation block no train
// sample sees a step time move, and a longer fit can drift it there
// (virtual-slave re-routing at 20 s: t_step went to 18.5 s and the
// validation gap grew 0.38 -> 0.85 N).
void polish(GapResult& g, TsmFrictionModel& model, const CandidateTrial& win, const GapOptions& o,
            const Say& say, std::vector<double>& f, ErrorMetrics& gap) {
  say("polishing the model with " + win.name);
  FitOptions ro = o.base_fit;
  ro.progress = nullptr;
  ro.global_stage = false;
  ro.starts = 1;
  ro.slip_copies_from_data = false;
  for (const auto& p : model.parameters()) {
    if (p.unit == "s" && !p.fixed) ro.bounds.push_back({p.name, p.value - 0.01, p.value + 0.01});
  }
  FitResult re = identify(model, g.data, ro);
  g.evaluations += re.evaluations;
  if (re.train_rmse < std::sqrt(win.train_mse)) {
    model.set_values(re.values);
    f = std::move(re.simulated);
    gap = error_metrics(g.data, f, SampleRole::kValidation);
  }
}

// The added friction against the variable the effect depends on, thinned
// to a few hundred points and sorted by the variable.
void describe_shape(const FitData& d, const TsmFrictionModel& model, TermKind kind,
                    EffectFound& e) {
  const auto& spec = model.spec();
  const bool asym = spec.has(TermKind::kDirectionAsymmetry);
  e.variable = variable_of(term_family(kind));
  if (kind == TermKind::kLoadScaling) e.variable = "distal_load";
  for (const auto& t : spec.terms) {
    if (t.kind != kind) continue;
    const std::size_t stride = std::max<std::size_t>(1, d.size() / 400);
    for (std::size_t i = 0; i < d.size(); i += stride) {
      const Motion& m = d.motion[i];
      if (is_multiplicative(kind)) {
        // The friction it adds: the other terms' level times (g - 1), with
        // the distal load taken from the measured friction.
        const double g = term_scaling(t, m, d.measured[i]);
        const double v = kind == TermKind::kLoadScaling ? m.distal : m.tension;
        e.shape.push_back({v, spec.gamma * sum_of_term_levels(spec.terms, m, asym) * (g - 1.0)});
        continue;
      }
      const double v = e.variable == std::string("x")      ? m.x
                       : e.variable == std::string("load") ? m.load
                       : e.variable == std::string("t")    ? m.t
                                                           : std::fabs(m.xd);
      e.shape.push_back({v, spec.gamma * term_level(t, m, asym)});
    }
  }
  std::sort(e.shape.begin(), e.shape.end());
}

// A structural effect for people: what it is, and what the data chose
// (the elements' number and spread, the copies' sizes).
EffectFound describe_structural(const TsmFrictionModel& model, Structural which) {
  const DistributedSlipSpec& s = model.spec().slip;
  EffectFound e;
  e.name = structural_family(which);
  e.form = structural_name(which);
  const auto add = [&](const std::string& name, double v) { e.parameters.push_back({name, v}); };
  switch (which) {
    case Structural::kDistributedSlip: {
      e.variable = "element_width";
      e.meaning =
          "distributed slip: slip spreads along the sheath, segment after segment, so the "
          "transition after a reversal is the sum of many elasto-slide elements (break "
          "displacements from stiff to compliant) instead of one hysteresis state";
      double total = 0.0;
      for (std::size_t k = 0; k < s.element_count(); ++k) {
        e.shape.push_back({s.width(k), s.weight[k]});
        total += s.weight[k];
      }
      e.where = "after each reversal, in the transition from sticking to sliding; the data chose " +
                std::to_string(s.elements) + " elements with widths " + num(s.width_min, 3) +
                " .. " + num(s.width_max, 3) + " rad" +
                (s.tendon_widths ? " per tendon (at the reference tension)" : "") +
                " (break forces " + num(total, 3) + " N in all)";
      add("distributed_slip.elements", s.elements);
      add("distributed_slip.width_min", s.width_min);
      add("distributed_slip.width_max", s.width_max);
      add("distributed_slip.smoothing", s.smoothing);
      break;
    }
    case Structural::kLoadCopies:
    case Structural::kTensionCopies: {
      const bool load = which == Structural::kLoadCopies;
      const auto& w = load ? s.load_weight : s.tension_weight;
      e.variable = load ? "distal_load" : "tension";
      const bool per_tendon = !load && s.drive_copies;
      e.meaning = load ? "capstan effect on the distal load: every slip element's break force and "
                         "the sliding friction scale with the load the tendons carry to the tip, "
                         "D = tau_out / R"
                  : per_tendon
                      ? "each sheath's friction scales with the tension its own tendon carries "
                        "(the capstan effect per tendon): every slip element and the sliding "
                        "friction scale with T1 and T3 apart"
                      : "the friction scales with the tension the tendons carry: every slip "
                        "element and the sliding friction scale with (T1 + T3) / 2";
      double sum = 0.0, base = 0.0;
      for (std::size_t k = 0; k < s.basis_count(); ++k) {
        const std::size_t i = s.basis_index(k);
        if (i < kSlidingIndex + 3) sum += w[i], base += s.weight[i];
      }
      // The relative growth of the break forces and Coulomb levels per N.
      const double per_n = base > 0.0 ? sum / base : 0.0;
      e.where = std::string(load ? "in contact, growing with the tip load"
                                 : "where the mean tendon tension changes") +
                "; the friction grows by " + num(100.0 * per_n, 3) + " % per N" +
                (load ? "" : " (reference " + num(s.tension_ref, 3) + " N)");
      add(load ? "distributed_slip.load_growth_per_N" : "distributed_slip.tension_growth_per_N",
          per_n);
      if (per_tendon) {
        // Sliding (every element saturated, the Coulomb function of the
        // direction at one), the friction's magnitude per N of each tendon's
        // tension: T = (T1 + T3) / 2 and u = T1 - T3 give t/2 + d per N of T1
        // and t/2 - d per N of T3. A sheath's capstan makes these about
        // 1 - e^(-mu wrap) for the tendon pulled and e^(mu wrap) - 1 for the
        // one released.
        const auto per = [&](std::size_t coulomb, double sign) {
          double growth = 0.0;
          for (std::size_t k = 0; k < s.basis_count(); ++k) {
            const std::size_t i = s.basis_index(k);
            if (i < kSlidingIndex || i == coulomb)
              growth += 0.5 * s.tension_weight[i] + sign * s.drive_weight[i];
          }
          return growth;
        };
        const std::size_t pos = kSlidingIndex, neg = kSlidingIndex + 1;
        add("tension_dependent.sliding_positive_per_N_T1", per(pos, 1.0));
        add("tension_dependent.sliding_positive_per_N_T3", per(pos, -1.0));
        add("tension_dependent.sliding_negative_per_N_T1", per(neg, 1.0));
        add("tension_dependent.sliding_negative_per_N_T3", per(neg, -1.0));
        e.where =
            "where the tendons' tensions change (tip loads raise one and lower the other; "
            "sheaths bent unequally give them unequal frictions); sliding, the friction's "
            "magnitude grows by " +
            num(per(pos, 1.0), 3) + " N per N of T1 and " + num(per(pos, -1.0), 3) +
            " N per N of T3 moving positive, " + num(per(neg, 1.0), 3) + " and " +
            num(per(neg, -1.0), 3) + " moving negative";
      }
      break;
    }
    case Structural::kTendonWidths: {
      // Each family's break forces, and the friction's growth per N of its
      // tendon's tension sliding (every element saturated at w_i g_j, the
      // copies' slopes on T = (T1 + T3) / 2 and u = T1 - T3 added).
      e.variable = "tension";
      e.meaning =
          "each sheath's friction scales with the tension its own tendon carries (the capstan "
          "effect per tendon), multiplicatively: its element family saturates at its break "
          "forces x g_j, g_j = max(T_j, 0) / T_ref, so the presliding widths and the break "
          "forces both grow with T_j and a slack tendon's sheath carries none";
      const std::size_t n = static_cast<std::size_t>(s.elements);
      double family[2] = {0.0, 0.0};
      for (std::size_t k = 0; k < 2 * n; ++k)
        family[k / n] += s.weight[k];
      const auto copies = [&](std::size_t coulomb, double sign) {
        double growth = 0.0;
        for (std::size_t k = 0; k < s.basis_count(); ++k) {
          const std::size_t i = s.basis_index(k);
          if (i < kSlidingIndex || i == coulomb)
            growth += (s.tension_copies ? 0.5 * s.tension_weight[i] : 0.0) +
                      (s.drive_copies ? sign * s.drive_weight[i] : 0.0);
        }
        return growth;
      };
      const double t1 = family[0] / s.tension_ref, t3 = family[1] / s.tension_ref;
      const std::size_t pos = kSlidingIndex, neg = kSlidingIndex + 1;
      const double pos_t1 = t1 + copies(pos, 1.0), pos_t3 = t3 + copies(pos, -1.0);
      const double neg_t1 = t1 + copies(neg, 1.0), neg_t3 = t3 + copies(neg, -1.0);
      add("tendon_widths.elements_per_tendon", s.elements);
      add("tendon_widths.tension_ref", s.tension_ref);
      add("tendon_widths.break_force_T1", family[0]);
      add("tendon_widths.break_force_T3", family[1]);
      add("tension_dependent.sliding_positive_per_N_T1", pos_t1);
      add("tension_dependent.sliding_positive_per_N_T3", pos_t3);
      add("tension_dependent.sliding_negative_per_N_T1", neg_t1);
      add("tension_dependent.sliding_negative_per_N_T3", neg_t3);
      e.where =
          "where the tendons' tensions change (tip loads raise one and lower the other; a tendon "
          "near slack loses its sheath's friction), in the transition after a reversal and "
          "sliding; per-tendon element families (" +
          std::to_string(s.elements) + " elements each, reference " + num(s.tension_ref, 3) +
          " N), break forces " + num(family[0], 3) + " N on T1 and " + num(family[1], 3) +
          " N on T3" + (s.tension_copies ? ", with tension copies" : "") +
          "; sliding, the friction's magnitude grows by " + num(pos_t1, 3) + " N per N of T1 and " +
          num(pos_t3, 3) + " N per N of T3 moving positive, " + num(neg_t1, 3) + " and " +
          num(neg_t3, 3) + " moving negative";
      break;
    }
    case Structural::kDistalSlip: {
      // The family's break forces against their widths.
      e.variable = "distal_angle";
      e.meaning =
          "slip driven from the tip: when the tip's load moves the tip while the input holds, "
          "the tendon stretches and the sheath slips from its distal end, which the input angle "
          "cannot show; a family of elasto-slide elements driven part of the way to the distal "
          "angle, x_in + a (x_out - x_in), follows it";
      double total = 0.0;
      for (std::size_t j = 0; j < s.distal_count(); ++j) {
        e.shape.push_back({s.distal_width(j), s.weight[kDistalIndex + j]});
        total += s.weight[kDistalIndex + j];
      }
      e.where =
          "where the tip moves apart from the input (its load changing in holds and slow "
          "motion); the data chose " +
          std::to_string(s.distal_elements) + " elements at a = " + num(s.distal_position, 3) +
          " of the way to the distal angle (break forces " + num(total, 3) + " N in all)";
      add("distributed_slip.distal_elements", s.distal_elements);
      add("distributed_slip.distal_position", s.distal_position);
      add("distal_slip.break_force", total);
      break;
    }
    case Structural::kSlipWithTension:
    case Structural::kSlipWithWidths:
      break;  // described as its two effects (accept_effect)
  }
  return e;
}

// The winner joins the model: polished, described, and the new current state.
void accept_effect(GapResult& g, GapState& cur, const CandidateTrial& win,
                   const std::vector<CandidateTrial>& round_trials, const GapOptions& o,
                   const Say& say) {
  const FitData& d = g.data;
  auto next_model = std::make_unique<TsmFrictionModel>(win.fitted);
  std::vector<double> f = simulate_friction(*next_model, d.motion);
  ErrorMetrics gap_after = win.validation;
  // A structural candidate's fit was already global in what it added.
  const std::optional<TermKind> term = term_kind_from_name(win.name);
  if (o.reidentify && term) polish(g, *next_model, win, o, say, f, gap_after);
  auto regimes_after = regime_errors(d, f, SampleRole::kValidation);
  if (!term) {
    const Structural which = *structural_from_name(win.name);
    const std::optional<Structural> copies = copies_of(which);
    const std::string fell = where_it_fell(cur.regimes, regimes_after);
    const double gain = 1.0 - gap_after.rmse / cur.gap.rmse;
    const std::string instead =
        win.replaces_hysteresis
            ? "; it replaces the base's Bouc-Wen hysteresis (the elements alone fitted better "
              "than beside it)"
            : "";
    if (copies) {
      // A pair: the elements and their copies, named as two effects. The
      // elements' line gives what they did alone in this round, the copies'
      // line what the pair did.
      const auto alone =
          std::find_if(round_trials.begin(), round_trials.end(), [](const CandidateTrial& t) {
            return t.name == structural_name(Structural::kDistributedSlip);
          });
      EffectFound slip = describe_structural(*next_model, Structural::kDistributedSlip);
      EffectFound copy = describe_structural(*next_model, *copies);
      slip.form = copy.form = win.name;
      const std::string alone_text =
          alone == round_trials.end() ? std::string("distributed slip alone was not tried")
                                      : "the elements alone shrank it by " + pct(alone->gain) +
                                            (alone->qualifies ? "" : " (not enough to be named)");
      slip.where += instead + "; named together with " + copy.name +
                    " (a stuck segment's break force is mu "
                    "times its local tension): " +
                    alone_text + ", with " + copy.name + " by " + pct(gain);
      copy.where += "; named together with distributed_slip (" + alone_text + ")";
      if (!fell.empty()) copy.where += "; residual fell most at " + fell;
      slip.gap_after = alone == round_trials.end() ? gap_after : alone->validation;
      slip.gain = 1.0 - slip.gap_after.rmse / cur.gap.rmse;
      copy.gap_after = gap_after;
      copy.gain = 1.0 - gap_after.rmse / slip.gap_after.rmse;
      g.effects.push_back(std::move(slip));
      g.effects.push_back(std::move(copy));
    } else {
      EffectFound e = describe_structural(*next_model, which);
      if (which == Structural::kDistributedSlip) e.where += instead;
      if (!fell.empty()) e.where += "; residual fell most at " + fell;
      e.gap_after = gap_after;
      e.gain = gain;
      g.effects.push_back(std::move(e));
    }
    say("found " + win.name + ": validation RMSE " + num(cur.gap.rmse) + " -> " +
        num(gap_after.rmse) + " N");
    cur = {std::move(next_model), std::move(f), gap_after, std::move(regimes_after)};
    return;
  }
  const TermKind kind = *term;

  EffectFound e;
  e.name = std::string(term_family(kind));
  e.form = win.name;
  e.meaning = std::string(term_info(kind).meaning);
  e.where = std::string(term_info(kind).where);
  const std::string own = own_regimes(kind, cur.regimes);
  if (!own.empty()) e.where += "; " + own;
  const std::string fell = where_it_fell(cur.regimes, regimes_after);
  if (!fell.empty()) e.where += "; residual fell most at " + fell;
  e.gap_after = gap_after;
  e.gain = 1.0 - gap_after.rmse / cur.gap.rmse;
  describe_shape(d, *next_model, kind, e);
  const auto params = next_model->parameters();
  for (std::size_t k = 0; k < term_info(kind).params.size(); ++k) {
    const auto name = qualified(kind, k);
    e.parameters.push_back({name, params[index_of(params, name)].value});
  }
  g.effects.push_back(std::move(e));
  say("found " + win.name + ": validation RMSE " + num(cur.gap.rmse) + " -> " +
      num(gap_after.rmse) + " N");
  cur = {std::move(next_model), std::move(f), gap_after, std::move(regimes_after)};
}

// Confounds: a rival that qualified in the round an effect was named, nearly
// as well, was never named afterwards, and after which the named effect adds
// nothing: the two explain the same residual. Never one confident name: both
// are reported, with the experiment that would separate them. When the named
// effect still adds after the rival, the rival only correlated with it; its
// "where" says so.
void find_confounds(GapResult& g, const GapOptions& o) {
  for (const auto& round : g.rounds) {
    if (round.accepted < 0) continue;
    const auto& win = round.trials[static_cast<std::size_t>(round.accepted)];
    for (const auto& rc : round.rivals) {
      // The effect this round named that the rival competes with (a family
      // is named once): a pair's copies for a load or tension rival, its
      // elements for any other (a hysteresis, a position term).
      const bool pair = adds_slip(win.name) && win.name != "distributed_slip";
      const std::string named_family =
          pair && rc.family != "load_dependent" && rc.family != "tension_dependent"
              ? std::string("distributed_slip")
              : win.family;
      const auto named_effect =
          std::find_if(g.effects.begin(), g.effects.end(),
                       [&](const EffectFound& e) { return e.name == named_family; });
      const bool named_later =
          std::any_of(g.effects.begin(), g.effects.end(),
                      [&](const EffectFound& e) { return e.name == rc.family; });
      if (named_later) continue;
      // The named effect must keep most of its own shrink on top of the
      // rival to count as told apart from it.
      if (rc.winner_still_qualifies && rc.winner_gain_after >= o.confound_extra * win.gain) {
        if (named_effect != g.effects.end())
          named_effect->where += "; " + rc.family + " alone also shrank the gap (" + pct(rc.gain) +
                                 "), but " + named_family + " still shrinks it by " +
                                 pct(rc.winner_gain_after) +
                                 " on top of it, and not the reverse: " + rc.family +
                                 " only correlates with it in this data";
        continue;
      }
      Confound c;
      c.named = named_family;
      c.rival = rc.family;
      c.named_gain = win.gain;
      c.rival_gain = rc.gain;
      c.experiment = separating_experiment(c.named, c.rival);
      c.warning = c.named + " and " + c.rival +
                  " are confounded in this recording: each alone shrinks the gap (" +
                  pct(c.named_gain) + " and " + pct(c.rival_gain) +
                  "), and neither adds much once the other is in (" + c.named + " after " +
                  c.rival + ": " + pct(rc.winner_gain_after) + "; " + c.rival + " after " +
                  c.named + ": below the margin). " + c.named +
                  " fitted slightly better, but the data cannot tell them apart; to separate "
                  "them, record " +
                  c.experiment;
      if (named_effect != g.effects.end()) named_effect->confounded_with.push_back(rc.family);
      g.confounds.push_back(std::move(c));
    }
  }
}

}  // namespace

ResidualDiagnostics diagnose_residual(const FitData& d, const TsmFrictionModel& model,
                                      std::span<const double> simulated,
                                      const std::vector<TermKind>& candidates) {
  ResidualDiagnostics diag;
  const auto r = residual_of(d, simulated);
  std::vector<double> val;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d.role[i] == SampleRole::kValidation) val.push_back(r[i]);
  }
  diag.lag1_autocorrelation = autocorrelation(val, 1);
  diag.correlation_time = correlation_time(val);
  const double n = static_cast<double>(val.size());
  for (std::size_t k = 1; k <= 20 && k < val.size(); ++k) {
    const double rho = autocorrelation(val, k);
    diag.ljung_box += n * (n + 2.0) * rho * rho / (n - static_cast<double>(k));
  }
  diag.white = diag.correlation_time < 2.0;
  for (TermKind kind : candidates) {
    if (model.spec().has(kind) || !data_has_variable(d, kind)) continue;
    const Prepared p = prepare_candidate(d, model, simulated, r, kind);
    diag.regressors.push_back({std::string(term_info(kind).name), p.explained});
  }
  std::sort(diag.regressors.begin(), diag.regressors.end(),
            [](const auto& a, const auto& b) { return a.explained > b.explained; });
  return diag;
}

GapResult find_model_gaps(const Recording& rec, const FrictionModel& base,
                          const std::string& base_name, const GapOptions& o) {
  return find_model_gaps(
      prepare_fit_data(rec, o.split, o.requirements, o.differentiator, o.derivatives, o.offline),
      base, base_name, o);
}

GapResult find_model_gaps(FitData data, const FrictionModel& base, const std::string& base_name,
                          const GapOptions& o) {
  const auto t_start = Clock::now();
  const auto* base_tsm = dynamic_cast<const TsmFrictionModel*>(&base);
  if (base_tsm == nullptr)
    throw std::invalid_argument(
        "tsm gap needs the composable tendon-sheath model (model: tsm; "
        "presets paper, dahl), not '" +
        base.kind() + "'");
  const Say say{o};
  const std::vector<TermKind> kinds = candidate_kinds(o);

  GapResult g;
  g.base_name = base_name;
  g.data = std::move(data);
  g.noise = noise_floor(g.data.measured);
  const FitData& d = g.data;

  // 1. The base model, fitted globally.
  fit_base(g, base, o, say);
  GapState cur{
      std::make_unique<TsmFrictionModel>(dynamic_cast<const TsmFrictionModel&>(*g.base_model)),
      g.base_simulated, g.gap_base, g.regimes_base};

  // 2-3. Rounds of candidates, until one stop rule holds.
  while (true) {
    GapRound round;
    round.before = cur.gap;
    std::vector<TermKind> todo;
    std::vector<Structural> structural;
    g.stop_reason = stop_before_round(g, cur, kinds, o, todo, structural);
    if (!g.stop_reason.empty()) break;
    run_trials(g, cur, todo, structural, o, say, t_start, round);
    if (!round.trials.front().qualifies) {
      const auto& best = round.trials.front();
      g.stop_reason =
          "no candidate qualifies: none shrinks the validation gap by >= " + pct(o.margin) +
          " or significantly (best: " + best.name + ", " + pct(best.gain) + ")";
      round.stop_reason = g.stop_reason;
      g.rounds.push_back(std::move(round));
      break;
    }
    round.accepted = 0;
    CandidateTrial& win = round.trials.front();
    win.accepted = true;
    check_rivals(g, win, o, say, round);
    accept_effect(g, cur, win, round.trials, o, say);
    g.rounds.push_back(std::move(round));
  }

  find_confounds(g, o);
  g.final_model = cur.model->clone();
  g.final_simulated = cur.f;
  g.gap_final = cur.gap;
  g.regimes_final = cur.regimes;
  g.diagnostics_base = diagnose_residual(d, dynamic_cast<const TsmFrictionModel&>(*g.base_model),
                                         g.base_simulated, kinds);
  g.diagnostics_final = diagnose_residual(d, *cur.model, g.final_simulated, kinds);
  g.seconds = std::chrono::duration<double>(Clock::now() - t_start).count();
  return g;
}

namespace {

nlohmann::json diagnostics_json(const ResidualDiagnostics& dg) {
  nlohmann::json regs = nlohmann::json::array();
  for (const auto& r : dg.regressors)
    regs.push_back({{"name", r.name}, {"explained", r.explained}});
  return nlohmann::json{{"lag1_autocorrelation", dg.lag1_autocorrelation},
                        {"correlation_time_samples", dg.correlation_time},
                        {"ljung_box_q20", dg.ljung_box},
                        {"white", dg.white},
                        {"candidate_regressors", regs}};
}

nlohmann::json effects_json(const std::vector<EffectFound>& found) {
  nlohmann::json effects = nlohmann::json::array();
  for (const auto& e : found) {
    nlohmann::json params = nlohmann::json::object();
    for (const auto& [name, value] : e.parameters)
      params[name] = value;
    nlohmann::json shape = nlohmann::json::array();
    for (const auto& [v, f] : e.shape)
      shape.push_back({v, f});
    effects.push_back({{"name", e.name},
                       {"form", e.form},
                       {"variable", e.variable},
                       {"shape", shape},
                       {"confounded_with", e.confounded_with},
                       {"confident", e.confounded_with.empty()},
                       {"where", e.where},
                       {"meaning", e.meaning},
                       {"gap_after", to_json(e.gap_after)},
                       {"gain", e.gain},
                       {"parameters", params}});
  }
  return effects;
}

nlohmann::json rounds_json(const std::vector<GapRound>& all) {
  nlohmann::json rounds = nlohmann::json::array();
  for (const auto& r : all) {
    nlohmann::json trials = nlohmann::json::array();
    for (const auto& t : r.trials) {
      trials.push_back({{"name", t.name},
                        {"family", t.family},
                        {"explained_first_order", t.explained},
                        {"validation", to_json(t.validation)},
                        {"gain", t.gain},
                        {"delta_bic", t.delta_bic},
                        {"z", t.z},
                        {"skipped", t.skipped},
                        {"excess_share", t.excess_share},
                        {"qualifies", t.qualifies},
                        {"accepted", t.accepted}});
    }
    nlohmann::json rivals = nlohmann::json::array();
    for (const auto& rc : r.rivals)
      rivals.push_back({{"family", rc.family},
                        {"gain", rc.gain},
                        {"accepted_gain_after_rival", rc.winner_gain_after},
                        {"accepted_still_qualifies", rc.winner_still_qualifies}});
    rounds.push_back(
        {{"gap_before", to_json(r.before)}, {"candidates", trials}, {"rivals", rivals}});
  }
  return rounds;
}

nlohmann::json confounds_json(const std::vector<Confound>& all) {
  nlohmann::json confounds = nlohmann::json::array();
  for (const auto& c : all) {
    confounds.push_back({{"named", c.named},
                         {"rival", c.rival},
                         {"named_gain", c.named_gain},
                         {"rival_gain", c.rival_gain},
                         {"experiment", c.experiment},
                         {"warning", c.warning}});
  }
  return confounds;
}

nlohmann::json acceptance_json(const GapOptions& o) {
  return {{"margin", o.margin},
          {"rule",
           "accept the candidate with the largest validation-RMSE reduction when it is "
           ">= margin, or when its improvement is significant (z >= min_z) and removes >= "
           "min_excess_share of the MSE above the noise floor; stop when none qualifies, or "
           "when the gap is within noise_stop x the "
           "noise floor. BIC (effective sample size) is reported with every trial"},
          {"noise_stop", o.noise_stop},
          {"min_z", o.min_z},
          {"min_excess_share", o.min_excess_share}};
}

}  // namespace

nlohmann::json gap_report_json(const GapResult& g, const GapOptions& o,
                               const std::vector<std::string>& plots, const std::string& plot_error,
                               double seconds) {
  nlohmann::json warnings = nlohmann::json::array();
  if (!plot_error.empty()) warnings.push_back("plots: " + plot_error);
  for (const auto& c : g.confounds)
    warnings.push_back(c.warning);
  return {{"tool", "tsm gap"},
          {"base", g.base_name},
          {"gap_base", to_json(g.gap_base)},
          {"effects", effects_json(g.effects)},
          {"gap_final", to_json(g.gap_final)},
          {"data",
           {{"source", g.data.source},
            {"samples", g.data.size()},
            {"duration_s", g.data.duration()},
            {"radius_m", g.data.radius_m},
            {"train_samples", g.data.count(SampleRole::kTrain)},
            {"validation_samples", g.data.count(SampleRole::kValidation)},
            {"block_s", g.data.block_s}}},
          {"noise_floor", g.noise},
          {"acceptance", acceptance_json(o)},
          {"regimes_base", to_json(g.regimes_base)},
          {"regimes_final", to_json(g.regimes_final)},
          {"diagnostics_base", diagnostics_json(g.diagnostics_base)},
          {"diagnostics_final", diagnostics_json(g.diagnostics_final)},
          {"rounds", rounds_json(g.rounds)},
          {"stop_reason", g.stop_reason},
          {"confounds", confounds_json(g.confounds)},
          {"noise_floor_ratio", g.noise > 0.0 ? g.gap_final.rmse / g.noise : 0.0},
          {"params_file", "params.yaml"},
          {"plots", plots},
          {"warnings", warnings},
          {"evaluations", g.evaluations},
          {"seconds", seconds}};
}

bool shape_is_flat(const std::vector<std::pair<double, double>>& shape) {
  return std::all_of(shape.begin(), shape.end(),
                     [](const auto& p) { return !(std::fabs(p.second) > 1e-12); });
}

std::string gap_summary_text(const GapResult& g, const GapOptions& o) {
  std::ostringstream s;
  const auto final_params = g.final_model ? g.final_model->parameters() : std::vector<Parameter>{};
  const auto final_value = [&](const std::string& name, double found) {
    for (const auto& p : final_params)
      if (p.name == name) return p.value;
    return found;
  };
  const auto metrics = [](const ErrorMetrics& m) {
    return "RMSE " + num(m.rmse) + " N, p2p " + num(m.p2p) + " N, fit " + num(m.fit_percent) + " %";
  };
  s << "tsm gap: " << g.data.source << " (" << num(g.data.duration(), 3) << " s), base model '"
    << g.base_name << "'\n\n";
  s << "Measurement noise on the friction (white part, from second differences): about "
    << num(g.noise) << " N.\n";
  s << "Base model fitted; gap on validation data: " << metrics(g.gap_base) << ".\n\n";
  s << "Where it disagreed (validation residual per regime; concentration = share of the squared "
       "error / share of the samples):\n";
  std::vector<const RegimeError*> worst;
  for (const auto& r : g.regimes_base)
    worst.push_back(&r);
  std::sort(worst.begin(), worst.end(),
            [](const auto* a, const auto* b) { return a->concentration > b->concentration; });
  for (std::size_t i = 0; i < worst.size() && i < 5; ++i) {
    const auto& r = *worst[i];
    s << "  " << r.name << " (" << r.where << "): RMSE " << num(r.metrics.rmse) << " N, "
      << num(r.concentration) << "x its share of the squared error\n";
  }
  // Systematic errors: the friction magnitude the model misses, per regime
  // (they show effects that do not change where the error is largest).
  std::vector<const RegimeError*> biased;
  for (const auto& r : g.regimes_base) {
    if (std::isfinite(r.magnitude_excess)) biased.push_back(&r);
  }
  std::sort(biased.begin(), biased.end(), [](const auto* a, const auto* b) {
    return std::fabs(a->magnitude_excess) > std::fabs(b->magnitude_excess);
  });
  s << "Largest systematic errors (measured minus model friction magnitude):\n";
  for (std::size_t i = 0; i < biased.size() && i < 4; ++i) {
    const auto& r = *biased[i];
    s << "  " << r.name << " (" << r.where << "): " << (r.magnitude_excess >= 0 ? "+" : "")
      << num(r.magnitude_excess) << " N ("
      << (r.magnitude_excess > 0 ? "model friction too small" : "model friction too large")
      << ")\n";
  }
  const auto& db = g.diagnostics_base;
  s << "Residual: " << (db.white ? "white" : "not white") << " (lag-1 autocorrelation "
    << num(db.lag1_autocorrelation) << ", correlation time " << num(db.correlation_time)
    << " samples).\nShare of the residual each candidate's regressor explains (first order):";
  for (const auto& r : db.regressors)
    s << " " << r.name << " " << pct(r.explained) << ";";
  s << "\n\n";
  for (std::size_t k = 0; k < g.rounds.size(); ++k) {
    const auto& r = g.rounds[k];
    s << "Round " << k + 1 << " (gap " << num(r.before.rmse) << " N): each candidate added and "
      << "refitted, validation RMSE change:\n";
    for (const auto& t : r.trials) {
      s << "  " << (t.accepted ? "* " : "  ") << t.name << ": " << num(t.validation.rmse) << " N ("
        << (t.gain >= 0 ? "-" : "+") << pct(std::fabs(t.gain)) << "), BIC "
        << (t.delta_bic < 0 ? "better" : "worse") << " by " << num(std::fabs(t.delta_bic)) << "\n";
    }
  }
  s << "\n";
  if (g.effects.empty()) s << "No missing effect found: " << g.stop_reason << ".\n";
  for (std::size_t k = 0; k < g.effects.size(); ++k) {
    const auto& e = g.effects[k];
    s << "Effect " << k + 1 << ": ";
    // Confounded: both names on the line, neither first with confidence.
    if (e.confounded_with.empty()) {
      s << e.name;
    } else {
      s << e.name;
      for (const auto& c : e.confounded_with)
        s << " or " << c;
      s << " (CONFOUNDED: this recording cannot tell " << e.name;
      for (const auto& c : e.confounded_with)
        s << " from " << c;
      s << "; see the warning below)";
    }
    s << " (form " << e.form << ") -- " << e.meaning << ".\n  Where: " << e.where
      << ".\n  Why: adding it shrinks the validation gap by " << pct(e.gain)
      << " (the acceptance margin is " << pct(o.margin) << "); now " << metrics(e.gap_after)
      << ".\n  Fitted (the final model, as in params.yaml):";
    // The values of the final model, refitted after every later effect: the
    // ones params.yaml holds, not those of the round that found the effect.
    for (const auto& [name, value] : e.parameters)
      s << " " << name << " = " << num(final_value(name, value), 4) << ";";
    s << "\n";
  }
  for (const auto& c : g.confounds)
    s << "\nWARNING: " << c.warning << ".\n";
  s << "\nGap before: " << metrics(g.gap_base) << "\nGap after:  " << metrics(g.gap_final) << " ("
    << (g.gap_base.rmse > 0 ? pct(1.0 - g.gap_final.rmse / g.gap_base.rmse) : "-")
    << " smaller RMSE); noise floor " << num(g.noise) << " N, final / floor "
    << num(g.noise > 0.0 ? g.gap_final.rmse / g.noise : 0.0) << "\nStopped: " << g.stop_reason
    << ".\n";
  return s.str();
}

}  // namespace tsmh::estimator
