// Accuracy sweep of `tsm fit` on the paper's model through
// realistic sensors (encoder quantum 2 pi/40960 rad, 3 mN m noise per torque
// channel, 40 s at 1 kHz), with the limits beside every figure. Not a ctest:
// a whole sweep takes minutes on 2 cores.
//
//   accuracy_fit derivs SEED...        true parameters on offline/deployed
//                                      derivatives vs the true friction
//   accuracy_fit fit SEED...           fit per seed: fitted vs true friction
//   accuracy_fit pipeline SEED...      fit on SEED, deployed causal estimator
//                                      on recording SEED+5000 of the same sheath
//   accuracy_fit gap CASE SEED...      tsm gap on a hidden effect; CASE one of
//                                      null viscous load position time
//                                      load+position viscous+time (the form of
//                                      each effect changes with the seed)
//   accuracy_fit csv-gap FILE...       tsm gap on recordings (virtual slave)
//
// Figures are RMSE over t >= 0.5 s in % of the true friction's peak.
// TSMH_MOTION=surgeon|reversals|creep runs fit/pipeline on another motion kind.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "estimator/distal_estimator.hpp"
#include "estimator/fit_workflow.hpp"
#include "estimator/model_gap.hpp"
#include "estimator/model_io.hpp"
#include "estimator/offline_derivatives.hpp"
#include "estimator/simulate.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"

using namespace tsmh::estimator;

namespace {

double peak_of(const std::vector<double>& v) {
  double p = 0.0;
  for (double x : v)
    p = std::max(p, std::fabs(x));
  return p;
}

// RMSE of a - b over t >= 0.5 s, % of peak.
double pct(const Recording& r, const std::vector<double>& a, const std::vector<double>& b,
           double peak) {
  double s = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (r.t[i] < r.t.front() + 0.5) continue;
    s += (a[i] - b[i]) * (a[i] - b[i]);
    ++n;
  }
  return 100.0 * std::sqrt(s / static_cast<double>(n)) / peak;
}

SyntheticData world(std::uint64_t seed) {
  SyntheticConfig c;
  c.seed = seed;
  // TSMH_MOTION=surgeon|reversals|creep: another motion kind (synthetic.hpp).
  if (const char* kind = std::getenv("TSMH_MOTION")) {
    if (const auto k = motion_kind_from_name(kind)) c.motion = *k;
  }
  c.exact_derivatives = true;  // for the limits only; the fit is given the file without them
  return make_synthetic(TsmFrictionModel(paper_spec()), c);
}

Recording without_derivatives(Recording r) {
  r.xd_in.clear();
  r.xdd_in.clear();
  return r;
}

std::vector<double> sim(const FrictionModel& m, const std::vector<Motion>& motion) {
  auto c = m.clone();
  return simulate_friction(*c, motion);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(
        stderr,
        "usage: accuracy_fit derivs|fit|pipeline SEED... | gap CASE SEED... | csv-gap FILE...\n");
    return 2;
  }
  const std::string mode = argv[1];
  std::vector<std::uint64_t> seeds;
  for (int i = 2; i < argc; ++i)
    seeds.push_back(std::strtoull(argv[i], nullptr, 10));  // (gap: argv[2] is the case)
  const TsmFrictionModel truth(paper_spec());
  double worst = 0.0, worst_limit = 0.0;

  if (mode == "derivs") {
    const double psds[] = {3, 10, 30};
    const double sigmas[] = {0.0, 0.5, -1.0};  // -1: the expected sign (erf)
    std::printf("seed  exact  deployed  offline[psd,sigmas] ...\n");
    for (auto seed : seeds) {
      const auto syn = world(seed);
      const double peak = peak_of(syn.true_friction);
      const auto& r = syn.recording;
      std::printf("%4llu %.3f %.3f", static_cast<unsigned long long>(seed),
                  pct(r, sim(truth, motion_from_recording(r, DerivativeSource::kExact)),
                      syn.true_friction, peak),
                  pct(r, sim(truth, motion_from_recording(r, DerivativeSource::kDifferentiator)),
                      syn.true_friction, peak));
      for (double q : psds)
        for (double sg : sigmas) {
          OfflineDerivativeConfig oc;
          oc.jerk_psd = q;
          oc.acc_sign_sigmas = sg < 0.0 ? 0.0 : sg;
          oc.expected_sign = sg < 0.0;
          std::printf("  [%g,%g] %.3f", q, sg,
                      pct(r, sim(truth, offline_motion(r, oc)), syn.true_friction, peak));
        }
      std::printf("\n");
    }
    return 0;
  }

  if (mode == "fit") {
    std::printf(
        "seed | fitted (offline motion) vs true F | limit: true params, same motion | fitted on "
        "exact motion vs true F | validation RMSE / floor (N) | verdict | fit s\n");
    for (auto seed : seeds) {
      const auto syn = world(seed);
      const double peak = peak_of(syn.true_friction);
      const Recording rec = without_derivatives(syn.recording);
      FitWorkflowOptions o;
      o.fit.seed = seed;
      const auto t0 = std::chrono::steady_clock::now();
      const FitRun run = run_fit(rec, TsmFrictionModel(paper_spec()), "paper", o);
      const double secs =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const double fitted = pct(rec, run.fit.simulated, syn.true_friction, peak);
      const double limit = pct(rec, sim(truth, run.data.motion), syn.true_friction, peak);
      const auto exact = motion_from_recording(syn.recording, DerivativeSource::kExact);
      const double fitted_exact = pct(rec, sim(*run.fit.model, exact), syn.true_friction, peak);
      worst = std::max(worst, fitted);
      worst_limit = std::max(worst_limit, limit);
      std::printf("%4llu | %.3f %% | %.3f %% | %.3f %% | %.4g / %.4g = %.3f | %s | %.2f\n",
                  static_cast<unsigned long long>(seed), fitted, limit, fitted_exact,
                  run.validation.rmse, run.noise, run.validation.rmse / run.noise,
                  run.verdict.grade.c_str(), secs);
      if (run.verdict.grade != "good")
        std::printf("      reason: %s\n", run.verdict.reason.c_str());
      for (const auto& w : run.uncertainty.warnings)
        std::printf("      warning: %s\n", w.c_str());
      std::fflush(stdout);
    }
    std::printf("worst: fitted %.3f %% of peak (limit %.3f %%)\n", worst, worst_limit);
    return 0;
  }

  if (mode == "pipeline") {
    std::printf(
        "fit seed -> run seed | fitted, deployed estimator vs true F | limit: true params, same "
        "estimator\n");
    for (auto seed : seeds) {
      const auto syn = world(seed);
      FitWorkflowOptions o;
      o.fit.seed = seed;
      o.uncertainty = false;
      const FitRun run =
          run_fit(without_derivatives(syn.recording), TsmFrictionModel(paper_spec()), "paper", o);
      const auto other = world(seed + 5000);
      const double peak = peak_of(other.true_friction);
      const Recording rec = without_derivatives(other.recording);
      // What `tsm simulate` and haptic-server do: the deployed causal
      // DistalTorqueEstimator, sample by sample.
      const auto causal = [&](const FrictionModel& m) {
        DistalTorqueEstimator est(m.clone(), rec.radius_m);
        std::vector<double> f(rec.size());
        for (std::size_t i = 0; i < rec.size(); ++i)
          f[i] = est.update(rec.t[i], rec.x_in[i], rec.tau_in[i]).friction;
        return f;
      };
      const double fitted = pct(rec, causal(*run.fit.model), other.true_friction, peak);
      const double limit = pct(rec, causal(truth), other.true_friction, peak);
      worst = std::max(worst, fitted);
      worst_limit = std::max(worst_limit, limit);
      std::printf("%4llu -> %llu | %.3f %% | %.3f %%\n", static_cast<unsigned long long>(seed),
                  static_cast<unsigned long long>(seed + 5000), fitted, limit);
      std::fflush(stdout);
    }
    std::printf("worst: %.3f %% of peak (limit %.3f %%)\n", worst, worst_limit);
    return 0;
  }
  if (mode == "gap" || mode == "csv-gap") {
    std::vector<std::string> inputs;
    std::string which;
    if (mode == "gap") {
      which = argv[2];
      seeds.erase(seeds.begin());
    } else {
      for (int i = 2; i < argc; ++i)
        inputs.push_back(argv[i]);
    }
    const std::size_t runs = mode == "gap" ? seeds.size() : inputs.size();
    std::printf(
        "case seed | hidden | named | gap base -> final (N) | noise floor (N) | final / "
        "floor | confounds | s\n");
    for (std::size_t k = 0; k < runs; ++k) {
      Recording rec;
      std::string hidden;
      if (mode == "gap") {
        const auto seed = seeds[k];
        TsmModelSpec spec = paper_spec();
        const int form = static_cast<int>(seed % 3);
        const auto add = [&](const std::string& family) {
          if (family == "viscous") {
            spec.add(TermKind::kViscous).p[0] = 0.1;
            hidden += "viscous(c_v 0.1) ";
          } else if (family == "load") {
            if (form == 1) {
              spec.add(TermKind::kLoadSaturating).p = {0.04, 5.0};
              hidden += "load_dependent(saturating 0.04, 5 N) ";
            } else {
              spec.add(TermKind::kLoadDependent).p[0] = 0.02;
              hidden += "load_dependent(linear 0.02) ";
            }
          } else if (family == "position") {
            if (form == 0) {
              spec.add(TermKind::kPositionDependent).p = {0.1, 0.1};
              hidden += "position_dependent(slope 0.1, 0.1) ";
            } else if (form == 1) {
              spec.add(TermKind::kPositionRipple).p = {0.08, 0.0, 9.4};
              hidden += "position_dependent(ripple 0.08, k 9.4) ";
            } else {
              spec.add(TermKind::kPositionBump).p = {0.15, 0.3, 0.15};
              hidden += "position_dependent(bump 0.15 at 0.3, w 0.15) ";
            }
          } else if (family == "time") {
            if (form == 2) {
              spec.add(TermKind::kTimeVarying).p = {0.004, 0.0, 1e6, 0.0};
              hidden += "time_varying(drift 0.004/s) ";
            } else {
              spec.add(TermKind::kTimeVarying).p = {0.0, 0.1, 25.0, 0.0};
              hidden += "time_varying(step 0.1 at 25 s) ";
            }
          }
        };
        std::string rest = which;
        while (!rest.empty()) {
          const auto plus = rest.find('+');
          const std::string part = rest.substr(0, plus);
          if (part != "null") add(part);
          rest = plus == std::string::npos ? "" : rest.substr(plus + 1);
        }
        SyntheticConfig c;
        c.seed = seed;
        rec = make_synthetic(TsmFrictionModel(spec), c).recording;
        if (hidden.empty()) hidden = "nothing";
      } else {
        rec = read_recording_csv(inputs[k]);
        hidden = inputs[k];
      }
      const auto t0 = std::chrono::steady_clock::now();
      const GapResult g = find_model_gaps(rec, TsmFrictionModel(paper_spec()), "paper");
      const double secs =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      std::string named, conf;
      for (const auto& e : g.effects)
        named += e.name + "[" + e.form + "] ";
      for (const auto& c : g.confounds)
        conf += c.named + "~" + c.rival + " ";
      if (named.empty()) named = "none";
      if (conf.empty()) conf = "-";
      std::printf("%s %llu | %s| %s| %.3f -> %.3f | %.3f | %.3f | %s | %.1f\n", which.c_str(),
                  static_cast<unsigned long long>(mode == "gap" ? seeds[k] : k), hidden.c_str(),
                  named.c_str(), g.gap_base.rmse, g.gap_final.rmse, g.noise,
                  g.gap_final.rmse / g.noise, conf.c_str(), secs);
      for (const auto& r : g.rounds) {
        std::printf("      round:");
        for (const auto& t : r.trials)
          std::printf(" %s %.1f%% (z %.1f, share %.2f)", t.name.c_str(), 100.0 * t.gain, t.z,
                      t.excess_share);
        std::printf("\n");
        for (const auto& rc : r.rivals)
          std::printf("      rival %s (%.1f%%): accepted effect after it %.1f%% (%s)\n",
                      rc.family.c_str(), 100.0 * rc.gain, 100.0 * rc.winner_gain_after,
                      rc.winner_still_qualifies ? "still qualifies" : "no longer qualifies");
      }
      std::fflush(stdout);
    }
    return 0;
  }
  std::fprintf(stderr, "unknown mode %s\n", mode.c_str());
  return 2;
}
