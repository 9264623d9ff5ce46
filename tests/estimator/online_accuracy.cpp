// The online estimate's accuracy suite: how close the deployed causal
// estimator (the DistalTorqueEstimator haptic-server and `tsm simulate` run,
// differentiator included) gets to the true friction, on paper-model data
// with realistic sensors, over many seeds and several motion kinds. Beside
// each figure, its limits: the same model and parameters given the exact
// derivatives at the same samples, the same with accelerations below a
// resolution unresolved (an oracle), and the offline smoother's derivatives;
// and the ambiguity no estimator from the encoder can get below: the same
// motion with a tremor, or a drift of either sign, too small to change any
// encoder sample.
// And one baseline below it: the plain causal polynomial (Savitzky-Golay)
// differentiator, as a reference.
//
// Run: build/bin/online_accuracy [--seeds N] [--first-seed S] [--kinds a,b]
//      [--jitter S] [--drops F] [--resolution A] [--sign-mode M] [--markdown]
//      [--tremor A] [--tremor-hz F] [--drift A] [--dump FILE.csv]
// Figures are % of the peak |true friction| of each recording; the verdict
// line holds every seed to the target, not the mean.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "causal_polyfit.hpp"
#include "estimator/distal_estimator.hpp"
#include "estimator/offline_derivatives.hpp"
#include "estimator/simulate.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"

namespace {

using namespace tsmh::estimator;

struct Case {
  std::string name;
  MotionKind kind;
  double f_low = 0.2, f_high = 1.0;           // multisine only
  bool within_target;                         // motion up to 1 Hz: the 1 % target applies
  double tremor_rad = 0.0, tremor_hz = 10.0;  // a tremor in the motion itself
};

// p2p as tsm fit scores it (docs/identification.md): max(e) - min(e).
struct Score {
  double rmse = 0.0, p2p = 0.0, max_abs = 0.0;  // % of peak |F_true|
};

double peak_abs(const std::vector<double>& v) {
  double peak = 0.0;
  for (double x : v)
    peak = std::max(peak, std::fabs(x));
  return peak;
}

// est against truth, in % of `peak`.
Score score(const std::vector<double>& est, const std::vector<double>& truth, double peak) {
  double se = 0.0, lo = 0.0, hi = 0.0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const double e = est[i] - truth[i];
    se += e * e;
    lo = i == 0 ? e : std::min(lo, e);
    hi = i == 0 ? e : std::max(hi, e);
  }
  return {100.0 * std::sqrt(se / static_cast<double>(truth.size())) / peak,
          100.0 * (hi - lo) / peak, 100.0 * std::max(hi, -lo) / peak};
}

Score score(const std::vector<double>& est, const std::vector<double>& truth) {
  return score(est, truth, peak_abs(truth));
}

struct Row {
  std::string kind;
  std::uint64_t seed;
  Score causal, exact, offline, resolved, polyfit;
  bool within_target;
  // Motions the encoder cannot tell from this one: the same with a
  // sub-resolution tremor added, and with a sub-resolution constant
  // acceleration of either sign. Encoder samples that differ from this
  // recording's (0 when they are indistinguishable), and half the RMSE
  // between the true frictions of a pair (this one and the tremor's; the
  // two drifts'), % of peak. The estimate from the encoder is the same for
  // both of a pair, so on one of them any estimator is off by at least this.
  std::size_t invisible_changed = 0;
  double ambiguity_tremor = 0.0, ambiguity_drift = 0.0;
  Score causal_tremor;
  // The causal error outside the encoder's stops (stop_windows()), and the
  // share of its square inside them: where the tendon creeps below one
  // encoder count, the paper's model keeps changing the friction through
  // lambda sgn(xdd) (eq. 4) while the encoder shows nothing.
  double causal_outside_stops = 0.0, stop_error_share = 0.0;
};

// Samples in an encoder stop: from the 50th ms without a new encoder value
// (when the rest correction takes the tendon as still) to 300 ms after the
// encoder moves again (while the friction state the stop left settles).
std::vector<bool> stop_windows(const std::vector<double>& t, const std::vector<double>& x) {
  constexpr double kStill = 0.05, kAfter = 0.3;
  std::vector<bool> in(t.size(), false);
  double changed_at = t.empty() ? 0.0 : t.front();
  double stop_ended = -std::numeric_limits<double>::infinity();
  bool stopped = false;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (i > 0 && x[i] != x[i - 1]) {
      if (stopped) stop_ended = t[i];
      stopped = false;
      changed_at = t[i];
    }
    if (t[i] - changed_at >= kStill) stopped = true;
    in[i] = stopped || t[i] - stop_ended <= kAfter;
  }
  return in;
}

// What the encoder can tell at all: the offline zero-phase derivatives that
// `tsm fit` uses (a Rauch-Tung-Striebel smoother over the whole record, future
// included; offline_derivatives.hpp) drive the same model. Not causal: a
// limit for the causal figure, never used online.
std::vector<double> offline_friction(const FrictionModel& truth, const Recording& rec,
                                     double quantum) {
  auto model = truth.clone();
  OfflineDerivativeConfig config;
  config.quantum = quantum;
  return simulate_friction(*model, offline_motion(rec, config));
}

Row run_case(const Case& c, std::uint64_t seed, double jitter, double drops,
             const DifferentiatorConfig& diff, const CorrectionsConfig& corrections,
             double resolution, double tremor, double tremor_hz, double drift,
             const std::string& dump_path) {
  const TsmFrictionModel truth(paper_spec());
  SyntheticConfig sc;
  sc.motion = c.kind;
  if (c.kind == MotionKind::kMultisine) {
    sc.f_low_hz = c.f_low;
    sc.f_high_hz = c.f_high;
  }
  sc.tremor_rad = c.tremor_rad;
  sc.tremor_hz = c.tremor_hz;
  sc.seed = seed;
  sc.exact_derivatives = true;
  sc.jitter_s = jitter;
  sc.drop_fraction = drops;
  sc.from_rest = true;
  sc.quantum = diff.quantum;
  const SyntheticData data = make_synthetic(truth, sc);
  const Recording& rec = data.recording;
  // The same motion with one of the invisible changes.
  const auto changed = [&](double add_tremor, double drift_acc) {
    SyntheticConfig v = sc;
    v.tremor_rad += add_tremor;
    // A motion with a tremor of its own gets the invisible one at its frequency.
    if (c.tremor_rad == 0.0) v.tremor_hz = tremor_hz;
    v.drift_acc = drift_acc;
    return make_synthetic(truth, v);
  };
  // A change that is off leaves the recording itself in its place.
  std::optional<SyntheticData> own_shaken, own_faster, own_slower;
  if (tremor > 0.0) own_shaken = changed(tremor, 0.0);
  if (drift > 0.0) own_faster = changed(0.0, drift), own_slower = changed(0.0, -drift);
  const SyntheticData& shaken = own_shaken ? *own_shaken : data;
  const SyntheticData& faster = own_faster ? *own_faster : data;
  const SyntheticData& slower = own_slower ? *own_slower : data;

  // The recordings start at rest with the true friction state at zero, so
  // the estimators start there too (the server's default tares the state
  // from the proximal torque instead: StartState::kFreeTip).
  DistalTorqueEstimator causal(truth.clone(), rec.radius_m, diff, StartState::kZero, corrections);
  DistalTorqueEstimator exact(truth.clone(), rec.radius_m, diff, StartState::kZero);
  // An oracle that knows the exact velocity and acceleration but, like any
  // estimator from this encoder, cannot tell the sign of an acceleration
  // smaller than `resolution`: there it takes xdd as 0 (eq. (4) without the
  // lambda term, branch (11)). Not an estimator: a measure of how much of the
  // model's output hangs on accelerations too small to resolve.
  DistalTorqueEstimator resolved(truth.clone(), rec.radius_m, diff, StartState::kZero);
  DistalTorqueEstimator polyfit(truth.clone(), rec.radius_m, diff, StartState::kZero);
  accuracy::CausalPolyFit poly_derivatives;
  std::vector<double> f_causal(rec.size()), f_exact(rec.size()), f_resolved(rec.size());
  std::vector<double> f_polyfit(rec.size());
  std::vector<Estimate> trace(dump_path.empty() ? 0 : rec.size());
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const Estimate e = causal.update(rec.t[i], rec.x_in[i], rec.tau_in[i]);
    f_causal[i] = e.friction;
    if (!trace.empty()) trace[i] = e;
    f_exact[i] =
        exact.update_exact(rec.t[i], rec.x_in[i], rec.xd_in[i], rec.xdd_in[i], rec.tau_in[i])
            .friction;
    const double xdd_seen = std::fabs(rec.xdd_in[i]) < resolution ? 0.0 : rec.xdd_in[i];
    f_resolved[i] =
        resolved.update_exact(rec.t[i], rec.x_in[i], rec.xd_in[i], xdd_seen, rec.tau_in[i])
            .friction;
    const auto [xd_fit, xdd_fit] = poly_derivatives.update(rec.t[i], rec.x_in[i]);
    f_polyfit[i] =
        polyfit.update_exact(rec.t[i], rec.x_in[i], xd_fit, xdd_fit, rec.tau_in[i]).friction;
  }
  const std::vector<double> f_offline = offline_friction(truth, rec, diff.quantum);
  if (!trace.empty()) {
    // One recording sample by sample, to look at where the error sits.
    std::FILE* f = std::fopen(dump_path.c_str(), "w");
    if (f == nullptr) {
      std::fprintf(stderr, "online_accuracy: cannot write %s\n", dump_path.c_str());
      std::exit(2);
    }
    std::fprintf(
        f, "t,x_in,xd_true,xd_est,xdd_true,xdd_est,sign_est,f_true,f_causal,f_exact,f_offline\n");
    for (std::size_t i = 0; i < rec.size(); ++i)
      std::fprintf(f, "%.4f,%.7f,%.6f,%.6f,%.5f,%.5f,%.4f,%.6f,%.6f,%.6f,%.6f\n", rec.t[i],
                   rec.x_in[i], rec.xd_in[i], trace[i].xd, rec.xdd_in[i], trace[i].xdd,
                   trace[i].acc_sign, data.true_friction[i], f_causal[i], f_exact[i], f_offline[i]);
    std::fclose(f);
  }
  // The recording starts at rest 1 s before t = 0 (from_rest), as the
  // estimators do, so truth and estimate share their initial state; that
  // warm-up second (a fade-in from rest for the multisine) is not scored.
  const auto skip =
      static_cast<std::size_t>(std::lower_bound(rec.t.begin(), rec.t.end(), 0.0) - rec.t.begin());
  const auto tail = [&](const std::vector<double>& v) {
    return std::vector<double>(v.begin() + static_cast<long>(skip), v.end());
  };
  const auto truth_tail = tail(data.true_friction);
  Row row{c.name,
          seed,
          score(tail(f_causal), truth_tail),
          score(tail(f_exact), truth_tail),
          score(tail(f_offline), truth_tail),
          score(tail(f_resolved), truth_tail),
          score(tail(f_polyfit), truth_tail),
          c.within_target,
          0,
          0.0,
          0.0,
          {},
          0.0,
          0.0};
  // The friction estimate depends on the encoder alone (the paper's model has
  // no load term), so where the samples agree it is the same for both truths.
  for (const SyntheticData* other : {&shaken, &faster, &slower}) {
    for (std::size_t i = 0; i < rec.size(); ++i)
      row.invisible_changed += other->recording.x_in[i] != rec.x_in[i] ? 1 : 0;
  }
  const auto shaken_tail = tail(shaken.true_friction);
  // In % of this recording's peak, as every other figure.
  const double peak = peak_abs(truth_tail);
  row.ambiguity_tremor = 0.5 * score(shaken_tail, truth_tail, peak).rmse;
  row.ambiguity_drift =
      0.5 * score(tail(faster.true_friction), tail(slower.true_friction), peak).rmse;
  row.causal_tremor = score(tail(f_causal), shaken_tail);
  const std::vector<bool> stops = stop_windows(tail(rec.t), tail(rec.x_in));
  const std::vector<double> causal_tail = tail(f_causal);
  double se_all = 0.0, se_stops = 0.0;
  std::vector<double> outside = truth_tail;  // errors in the stops counted as 0
  for (std::size_t i = 0; i < truth_tail.size(); ++i) {
    const double e = causal_tail[i] - truth_tail[i];
    se_all += e * e;
    if (stops[i])
      se_stops += e * e;
    else
      outside[i] = causal_tail[i];
  }
  row.causal_outside_stops = score(outside, truth_tail, peak).rmse;
  row.stop_error_share = se_all > 0.0 ? se_stops / se_all : 0.0;
  return row;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Accuracy of the online (causal) distal torque estimate over many seeds"};
  int seeds = 10;
  std::uint64_t first_seed = 1;
  std::string kinds = "multisine,surgeon,reversals,creep,multisine-fast,surgeon-tremor";
  double jitter = 0.0, drops = 0.0;
  bool markdown = false;
  std::string dump;
  double resolution = 0.01;
  double tremor = 1e-12, tremor_hz = 10.0, drift = 1e-16;
  app.add_option("--seeds", seeds, "Seeds per motion kind")->check(CLI::PositiveNumber);
  app.add_option("--first-seed", first_seed, "First seed");
  app.add_option("--kinds", kinds,
                 "Comma-separated: multisine (0.2-1 Hz), multisine-fast (1-2 Hz), surgeon, "
                 "reversals, creep, surgeon-tremor (surgeon with a 0.2 mrad 9 Hz tremor)");
  app.add_option("--jitter", jitter, "Sampling jitter, s (uniform +-)")
      ->check(CLI::Range(0.0, 4e-4));
  app.add_option("--drops", drops, "Fraction of samples lost")->check(CLI::Range(0.0, 0.5));
  app.add_flag("--markdown", markdown, "Print the table as markdown");
  app.add_option("--dump", dump,
                 "CSV of the first seed of the first kind, sample by sample (truth, estimates)");
  app.add_option("--resolution", resolution,
                 "Oracle limit: exact derivatives, acceleration below this (rad/s^2) taken as 0")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--tremor", tremor,
                 "Ambiguity: the same motion with this tremor (rad, at --tremor-hz) added, which "
                 "changes no encoder sample (0: off)")
      ->check(CLI::Range(0.0, 1e-6));
  app.add_option("--tremor-hz", tremor_hz, "... its frequency, Hz")->check(CLI::Range(0.1, 100.0));
  app.add_option("--drift", drift,
                 "Ambiguity: the same motion with a constant acceleration of +- this (rad/s^2) "
                 "added, which changes no encoder sample (0: off)")
      ->check(CLI::Range(0.0, 1e-9));
  DifferentiatorConfig diff{};
  CorrectionsConfig corrections{};
  HindsightConfig& hindsight = corrections.hindsight;
  app.add_option("--encoder-quantum", diff.quantum,
                 "Encoder resolution of x_in, rad: the recordings' and the differentiator's")
      ->check(CLI::Validator(
          [](std::string& value) -> std::string {
            const char* problem =
                DifferentiatorLimits::encoder_quantum_problem(std::strtod(value.c_str(), nullptr));
            return problem == nullptr ? "" : std::string(problem) + ", got " + value;
          },
          "(0, 0.1]"));
  app.add_option("--jerk-psd", diff.jerk_psd, "Velocity channel jerk PSD (default as deployed)");
  app.add_option("--snap-psd", diff.snap_psd, "Acceleration channel snap PSD");
  app.add_option("--fine-psd", diff.fine_psd,
                 "Fine acceleration channel crackle PSD (0: off; smooth sign)");
  app.add_option("--fine-consistency", diff.fine_consistency,
                 "smooth sign: the fine channel decides within this many fast sd of it");
  app.add_option("--hindsight-lag", hindsight.lag,
                 "Hindsight correction: lag, s (0: off; smooth sign with the fine channel)");
  app.add_option("--hindsight-sure", hindsight.sure, "... |xdd| where it starts to count");
  app.add_option("--hindsight-certain", hindsight.certain, "... |xdd| where it decides");
  app.add_option("--hindsight-sure-armed", hindsight.sure_armed,
                 "... |xdd| where it starts to count shortly after a manoeuvre");
  app.add_option("--hindsight-certain-armed", hindsight.certain_armed,
                 "... |xdd| where it decides shortly after a manoeuvre");
  app.add_option("--hindsight-guard", hindsight.guard,
                 "... none within this long (s) of a manoeuvre");
  app.add_option("--hindsight-ahead", hindsight.ahead,
                 "... after a correction, samples up to this much younger (s) in the same pass");
  app.add_option("--slow-jerk-psd", diff.slow_jerk_psd,
                 "Slow acceleration channel jerk PSD (0: off, the fast channel alone)");
  app.add_option("--slow-consistency", diff.slow_consistency,
                 "smooth sign: the slow channel decides within this many fast sd of it");
  app.add_option("--slow-sigmas", diff.slow_sigmas,
                 "smooth sign from the slow channel: width in sd");
  app.add_option("--sign-sigmas", diff.sign_sigmas, "sgn(xdd) decided beyond this many sd");
  app.add_option("--sign-release", diff.sign_release, "... and released below this many sd");
  app.add_option("--cruise-window", corrections.cruise_window,
                 "smooth sign: cruise hypothesis window, s (0: off)");
  app.add_option("--cruise-prior", corrections.cruise_prior, "... its prior probability");
  app.add_option("--cruise-nis", corrections.cruise_nis,
                 "... armed when the acceleration channel's NIS (5 ms) exceeds this");
  app.add_option("--cruise-armed-time", corrections.cruise_armed_time, "... for this long, s");
  app.add_option("--cruise-noise", corrections.cruise_noise,
                 "... its samples' error variance in quantisation variances");
  std::string sign_mode = "smooth";
  app.add_option("--sign-mode", sign_mode, "smooth (deployed), smooth-fast or hard");
  app.add_flag("--exact-covariance", diff.exact_covariance, "full Kalman recursion every sample");
  app.add_option("--smooth-sigmas", diff.smooth_sigmas, "smooth sign: width in sd");
  app.add_option("--still-time", corrections.still_time,
                 "encoder unchanged this long (s): rest (default automatic: 50 ms at 2 pi/40960 "
                 "rad, with the cube root of the quantum)");
  CLI11_PARSE(app, argc, argv);
  const auto mode = sign_mode_from_name(sign_mode);
  if (!mode) {
    std::fprintf(stderr, "online_accuracy: --sign-mode must be smooth, smooth-fast or hard\n");
    return 2;
  }
  diff.sign_mode = *mode;

  const std::vector<Case> all{
      {"multisine", MotionKind::kMultisine, 0.2, 1.0, true},
      {"surgeon", MotionKind::kSurgeon, 0, 0, true},
      {"reversals", MotionKind::kReversals, 0, 0, true},
      {"creep", MotionKind::kCreep, 0, 0, true},
      {"multisine-fast", MotionKind::kMultisine, 1.0, 2.0, false},
      // A hand's physiological tremor left in the slave's motion (8-12 Hz;
      // 0.2 mrad is 1.3 encoder counts): faster than the 1 Hz target.
      {"surgeon-tremor", MotionKind::kSurgeon, 0, 0, false, 2e-4, 9.0},
  };
  std::vector<Case> cases;
  std::size_t pos = 0;
  while (pos <= kinds.size()) {
    const std::size_t end = std::min(kinds.find(',', pos), kinds.size());
    const std::string name = kinds.substr(pos, end - pos);
    const auto it =
        std::find_if(all.begin(), all.end(), [&](const Case& c) { return c.name == name; });
    if (it == all.end()) {
      std::fprintf(stderr, "online_accuracy: unknown motion kind '%s'\n", name.c_str());
      return 2;
    }
    cases.push_back(*it);
    pos = end + 1;
  }

  std::vector<Row> rows;
  for (const auto& c : cases) {
    for (int s = 0; s < seeds; ++s)
      rows.push_back(run_case(c, first_seed + static_cast<std::uint64_t>(s), jitter, drops, diff,
                              corrections, resolution, tremor, tremor_hz, drift,
                              rows.empty() ? dump : std::string{}));
  }

  if (markdown) {
    std::printf(
        "| motion | seed | causal RMSE %% | causal p2p %% | causal max %% | offline (RTS) RMSE "
        "%% | exact, \\|xdd\\| < %g unresolved, RMSE %% | exact-derivative RMSE %% | "
        "exact-derivative p2p %% | baseline: causal quadratic fits, RMSE %% | ambiguity, "
        "tremor %g rad at %g Hz, %% | ambiguity, drift +-%g rad/s^2, %% | causal vs the "
        "tremor's truth, RMSE %% | causal outside encoder stops, RMSE %% | share of the "
        "causal squared error in encoder stops |\n",
        resolution, tremor, tremor_hz, drift);
    std::printf(
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- "
        "|\n");
  } else {
    std::printf("%-15s %5s %12s %12s %12s %12s %12s %12s %12s %12s %12s %12s %12s %12s %12s\n",
                "motion", "seed", "causal_rmse%", "causal_p2p%", "causal_max%", "offline_rmse%",
                "resolved_rmse%", "exact_rmse%", "exact_p2p%", "polyfit_rmse%", "amb_tremor%",
                "amb_drift%", "vs_tremor%", "outside_stop%", "stop_share");
  }
  for (const auto& r : rows) {
    const auto seed = static_cast<unsigned long long>(r.seed);
    const double values[] = {r.causal.rmse,     r.causal.p2p,         r.causal.max_abs,
                             r.offline.rmse,    r.resolved.rmse,      r.exact.rmse,
                             r.exact.p2p,       r.polyfit.rmse,       r.ambiguity_tremor,
                             r.ambiguity_drift, r.causal_tremor.rmse, r.causal_outside_stops,
                             r.stop_error_share};
    const int decimals[] = {3, 2, 2, 3, 3, 3, 3, 3, 3, 3, 3, 3, 2};
    if (markdown)
      std::printf("| %s | %llu |", r.kind.c_str(), seed);
    else
      std::printf("%-15s %5llu", r.kind.c_str(), seed);
    for (std::size_t k = 0; k < std::size(values); ++k) {
      if (markdown)
        std::printf(" %.*f |", decimals[k], values[k]);
      else
        std::printf(" %12.*f", decimals[k], values[k]);
    }
    std::printf("\n");
  }
  std::size_t changed = 0;
  for (const auto& r : rows)
    changed += r.invisible_changed;
  // The ambiguity bounds every estimator only where the perturbed motions
  // left every encoder sample as it was.
  const bool bound = changed == 0 && (tremor > 0.0 || drift > 0.0);
  if (changed > 0)
    std::printf(
        "note: the perturbations changed %zu encoder samples; the ambiguity columns are "
        "then not a bound\n",
        changed);
  std::printf("\nworst case per motion kind (%% of peak friction):\n");
  bool all_ok = true;
  std::string above, undecidable;  // kinds up to 1 Hz above 1 %; of them, out of any reach
  for (const auto& c : cases) {
    double worst = 0.0, worst_max = 0.0, worst_exact = 0.0, worst_offline = 0.0;
    double worst_resolved = 0.0, worst_polyfit = 0.0, worst_p2p = 0.0, worst_exact_p2p = 0.0;
    double worst_outside = 0.0, worst_share = 0.0;  // the worst seed's share of its error in stops
    // Every seed's ambiguity is a bound on that seed: the least over the seeds
    // says whether the target can hold on every one.
    double least_ambiguity = std::numeric_limits<double>::infinity(), most_ambiguity = 0.0;
    for (const auto& r : rows) {
      if (r.kind != c.name) continue;
      if (r.causal.rmse >= worst) worst_share = r.stop_error_share;
      worst = std::max(worst, r.causal.rmse);
      worst_outside = std::max(worst_outside, r.causal_outside_stops);
      worst_max = std::max(worst_max, r.causal.max_abs);
      worst_p2p = std::max(worst_p2p, r.causal.p2p);
      worst_exact_p2p = std::max(worst_exact_p2p, r.exact.p2p);
      worst_exact = std::max(worst_exact, r.exact.rmse);
      worst_offline = std::max(worst_offline, r.offline.rmse);
      worst_resolved = std::max(worst_resolved, r.resolved.rmse);
      worst_polyfit = std::max(worst_polyfit, r.polyfit.rmse);
      const double ambiguity = std::max(r.ambiguity_tremor, r.ambiguity_drift);
      least_ambiguity = std::min(least_ambiguity, ambiguity);
      most_ambiguity = std::max(most_ambiguity, ambiguity);
    }
    const bool ok = worst <= 1.0;
    if (c.within_target) all_ok = all_ok && ok;
    if (c.within_target && !ok) {
      above += (above.empty() ? "" : ", ") + c.name;
      if (bound && least_ambiguity > 1.0) undecidable += (undecidable.empty() ? "" : ", ") + c.name;
    }
    const char* verdict =
        c.within_target ? (ok ? "within 1 %" : "ABOVE 1 %") : "(faster than 1 Hz: reported)";
    // Where the ambiguity exceeds 1 %, the generator's motion is met (or
    // not) by how an estimator breaks a tie the encoder cannot see.
    const char* why = "";
    if (c.within_target && bound && most_ambiguity > 1.0) {
      if (least_ambiguity <= 1.0)
        why =
            " (on some seeds no estimator from the encoder is within 1 % on both of two "
            "motions with the same encoder samples)";
      else if (ok)
        why =
            " (on this motion; on every seed no estimator from the encoder is within 1 % on "
            "both of two motions with the same encoder samples)";
      else
        why =
            " (on every seed so is any estimator from the encoder, on one of two motions with "
            "the same encoder samples)";
    }
    std::printf(
        "  %-15s causal RMSE %.3f (p2p %.2f, max %.2f); limits: offline zero-phase %.3f, exact "
        "but |xdd| < %g unresolved %.3f, exact derivatives %.3f (p2p %.2f); baseline causal "
        "quadratic fits %.3f; ambiguity %.3f-%.3f; outside encoder stops %.3f (worst seed: "
        "%.0f %% of its squared error in stops)  %s%s\n",
        c.name.c_str(), worst, worst_p2p, worst_max, worst_offline, resolution, worst_resolved,
        worst_exact, worst_exact_p2p, worst_polyfit, least_ambiguity, most_ambiguity, worst_outside,
        100.0 * worst_share, verdict, why);
  }
  if (all_ok)
    std::printf("verdict: every seed of every kind up to 1 Hz within 1 %% of peak\n");
  else
    std::printf("verdict: some seed above 1 %% of peak (%s)%s%s%s\n", above.c_str(),
                undecidable.empty() ? "" : "; ", undecidable.c_str(),
                undecidable.empty()
                    ? ""
                    : ": on every seed no estimator from the encoder is within 1 % on both "
                      "of two motions it cannot tell apart (ambiguity)");
  return all_ok ? 0 : 1;
}
