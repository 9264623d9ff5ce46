// Identification (`tsm fit`) on synthetic data with a known truth:
// accuracy from several starting guesses, determinism, a simpler (Dahl)
// world, garbage refused, parameter uncertainty, and the CLI's outputs.
//
// Acceptance seeds 101, 202, 303 were not used while developing the fit
// (development used 11-13, 21-25 and 31-50; for the Levenberg-Marquardt fit, 1-6).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "estimator/baselines.hpp"
#include "estimator/fit_workflow.hpp"
#include "estimator/model_io.hpp"
#include "estimator/simulate.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

double peak_of(const std::vector<double>& v) {
  double p = 0.0;
  for (double x : v)
    p = std::max(p, std::fabs(x));
  return p;
}

double validation_rmse(const FitData& d, std::span<const double> a, std::span<const double> b) {
  return error_metrics(a, b, [&](std::size_t i) { return d.role[i] == SampleRole::kValidation; })
      .rmse;
}

// A start far from the truth: levels halved, theta tripled, shapes off.
TsmModelSpec far_start() {
  TsmModelSpec s = paper_spec();
  s.theta *= 3.0;
  s.sigma = 2.0;
  for (auto& t : s.terms) {
    for (auto& p : t.p)
      p *= 0.5;
  }
  return s;
}

// The paper's structure with Dahl-like values: no Stribeck, no acceleration
// dependence, no reversal offset, one level.
TsmModelSpec flat_start() {
  TsmModelSpec s = paper_spec();
  s.terms[0].p[0] = 1.0;                     // rho1
  s.terms[1].p[0] = 1.0;                     // rho2
  s.terms[2].p = {0.0, 1.0};                 // stribeck
  s.terms[3].p = {0.0, 0.0, 0.0, 1.0, 1.0};  // acceleration_dependence
  s.terms[4].p[0] = 0.0;                     // lambda
  return s;
}

struct Acceptance {
  double identified_pct;  // fitted vs true model, both on the fit's (offline) motion
  double fitted_pct;      // fitted (offline motion) vs the true friction
  double limit_pct;       // true parameters (offline motion) vs the true friction
  double exact_pct;       // fitted on the exact motion vs the true friction
  FitRun run;
};

Acceptance accept(std::uint64_t seed, const TsmModelSpec& start) {
  SyntheticConfig c;
  c.seed = seed;
  c.exact_derivatives = true;  // for the exact-motion comparison only
  const TsmFrictionModel truth(paper_spec());
  const auto syn = make_synthetic(truth, c);
  Recording rec = syn.recording;  // what a user records: no derivative columns
  rec.xd_in.clear();
  rec.xdd_in.clear();
  FitWorkflowOptions o;
  o.fit.seed = seed;
  Acceptance a{0, 0, 0, 0, run_fit(rec, TsmFrictionModel(start), "test", o)};
  const FitData& d = a.run.data;
  const double peak = peak_of(syn.true_friction);
  auto t = truth.clone();
  const auto true_offline = simulate_friction(*t, d.motion);
  const auto exact_motion = motion_from_recording(syn.recording, DerivativeSource::kExact);
  const auto fitted_exact = simulate_friction(*a.run.fit.model, exact_motion);
  a.identified_pct = 100.0 * validation_rmse(d, true_offline, a.run.fit.simulated) / peak;
  a.fitted_pct = 100.0 * validation_rmse(d, syn.true_friction, a.run.fit.simulated) / peak;
  a.limit_pct = 100.0 * validation_rmse(d, syn.true_friction, true_offline) / peak;
  a.exact_pct = 100.0 * validation_rmse(d, syn.true_friction, fitted_exact) / peak;
  return a;
}

void check(const Acceptance& a) {
  ::testing::Test::RecordProperty("identified_pct_of_peak", std::to_string(a.identified_pct));
  ::testing::Test::RecordProperty("fitted_pct_of_peak", std::to_string(a.fitted_pct));
  ::testing::Test::RecordProperty("true_params_same_motion_pct", std::to_string(a.limit_pct));
  ::testing::Test::RecordProperty("exact_motion_pct_of_peak", std::to_string(a.exact_pct));
  ::testing::Test::RecordProperty("validation_fit_percent",
                                  std::to_string(a.run.validation.fit_percent));
  EXPECT_EQ(a.run.data.derivatives, "offline");
  // The fitted friction within 1 % of the true friction's peak...
  EXPECT_LE(a.fitted_pct, 1.0);
  // ...and on exact motion too (the parameters are the physical ones)...
  EXPECT_LE(a.exact_pct, 1.0);
  // ...no worse than the true parameters on the same derivatives, beyond 0.2 %.
  EXPECT_LE(a.fitted_pct, a.limit_pct + 0.2);
  EXPECT_EQ(a.run.verdict.grade, "good") << a.run.verdict.reason;
}

TEST(IdentificationAcceptance, PaperWorldFromThePaperValues) {
  check(accept(101, paper_spec()));
}

TEST(IdentificationAcceptance, PaperWorldFromAFarStart) {
  check(accept(202, far_start()));
}

TEST(IdentificationAcceptance, PaperWorldFromDahlLikeValues) {
  check(accept(303, flat_start()));
}

TEST(Identification, DahlWorldIsFittedWellByThePaperModel) {
  SyntheticConfig c;
  c.seed = 404;
  const DahlModel truth;  // sigma0 148.4 N/rad, Fc 9.2 N
  const auto syn = make_synthetic(truth, c);
  const FitRun run = run_fit(syn.recording, TsmFrictionModel(paper_spec()), "paper");
  RecordProperty("validation_fit_percent", std::to_string(run.validation.fit_percent));
  EXPECT_GT(run.validation.fit_percent, 90.0);
  const double vs_truth = validation_rmse(run.data, syn.true_friction, run.fit.simulated);
  RecordProperty("rmse_vs_truth_N", std::to_string(vs_truth));
  EXPECT_LE(vs_truth, 0.05 * peak_of(syn.true_friction));
  // The paper's model (n = 2) cannot take Dahl's shape (n = 1) exactly: the
  // residual stays above the noise floor, and the verdict must say so with
  // the figures instead of calling it good.
  const double ratio = run.validation.rmse / run.noise;
  RecordProperty("rmse_over_noise_floor", std::to_string(ratio));
  if (ratio > 1.2) {
    EXPECT_NE(run.verdict.grade, "good") << run.verdict.reason;
    EXPECT_NE(run.verdict.reason.find("beyond the noise unexplained"), std::string::npos)
        << run.verdict.reason;
  }
}

TEST(Identification, GarbageWithoutMotionIsRefusedWithAReason) {
  SyntheticConfig c;
  c.amplitude_rad = 1e-6;  // the joint does not move; the torques are noise
  const auto syn = make_synthetic(TsmFrictionModel(paper_spec()), c);
  try {
    run_fit(syn.recording, TsmFrictionModel(paper_spec()), "paper");
    FAIL() << "fitting data without motion must be refused";
  } catch (const DataError& e) {
    EXPECT_NE(std::string(e.what()).find("no motion"), std::string::npos) << e.what();
    EXPECT_EQ(e.column(), "x_in");
  }
}

TEST(Identification, DeterministicForASeedWhateverTheThreads) {
  SyntheticConfig c;
  c.seed = 9;
  c.duration_s = 10.0;
  const auto syn = make_synthetic(TsmFrictionModel(paper_spec()), c);
  const FitData d = prepare_fit_data(syn.recording);
  FitOptions o;
  o.seed = 77;
  o.starts = 3;
  o.global_evaluations = 300;
  o.coarse_local_evaluations = 60;
  o.local_evaluations = 30;
  o.threads = 1;
  const auto a = identify(TsmFrictionModel(paper_spec()), d, o);
  o.threads = 2;
  const auto b = identify(TsmFrictionModel(paper_spec()), d, o);
  EXPECT_EQ(a.values, b.values);
  EXPECT_EQ(a.best_start, b.best_start);
  // The nlopt method too (its starts are random, seeded).
  o.method = "nlopt";
  o.threads = 1;
  const auto c1 = identify(TsmFrictionModel(paper_spec()), d, o);
  o.threads = 2;
  const auto c2 = identify(TsmFrictionModel(paper_spec()), d, o);
  EXPECT_EQ(c1.values, c2.values);
  o.seed = 78;
  const auto other = identify(TsmFrictionModel(paper_spec()), d, o);
  EXPECT_NE(other.starts[1].global_rmse, c1.starts[1].global_rmse) << "the seed must matter";
  // The result is never worse than the starting values.
  auto start = TsmFrictionModel(paper_spec());
  const auto f0 = simulate_friction(start, d.motion);
  EXPECT_LE(a.train_rmse,
            std::sqrt(weighted_mse(d.measured, f0, d.weights(SampleRole::kTrain))) + 1e-9);
}

// The paper's model is the distributed model's special case (slip weights
// zero): on the paper model's own data (a multisine, seed 1, where the
// elements alone stopped at 9.0x the sensor floor) `tsm fit --model
// distributed` keeps the paper's hysteresis beside the elements and reaches
// the floor.
TEST(Identification, DistributedFitFindsThePaperModelOnItsData) {
  SyntheticConfig c;
  c.seed = 1;
  const auto syn = make_synthetic(TsmFrictionModel(paper_spec()), c);
  FitWorkflowOptions o;
  o.uncertainty = false;
  const FitRun run = run_fit(syn.recording, TsmFrictionModel(distributed_spec()), "distributed", o);
  const auto* tsm = dynamic_cast<const TsmFrictionModel*>(run.fit.model.get());
  ASSERT_NE(tsm, nullptr);
  EXPECT_TRUE(tsm->spec().slip.enabled);
  EXPECT_FALSE(tsm->spec().terms.empty());
  const auto measured = syn.recording.measured_friction();
  double se = 0.0;
  for (std::size_t i = 0; i < measured.size(); ++i)
    se += (measured[i] - syn.true_friction[i]) * (measured[i] - syn.true_friction[i]);
  const double floor = std::sqrt(se / static_cast<double>(measured.size()));
  EXPECT_LT(run.validation.rmse / floor, 1.1)
      << "validation " << run.validation.rmse << " N, floor " << floor << " N";
}

TEST(Identification, WarmRefitOnlyPolishes) {
  SyntheticConfig c;
  c.seed = 10;
  c.duration_s = 10.0;
  const auto syn = make_synthetic(TsmFrictionModel(paper_spec()), c);
  const FitData d = prepare_fit_data(syn.recording);
  FitOptions o;
  o.global_stage = false;
  o.starts = 2;
  o.local_evaluations = 40;
  o.coarse_local_evaluations = 40;
  const auto r = identify(TsmFrictionModel(paper_spec()), d, o);
  EXPECT_TRUE(r.global_algorithm.empty());
  // No informed grid: only the given values and one perturbation of them.
  EXPECT_EQ(r.screened, 2);
  o.method = "nlopt";
  const auto n = identify(TsmFrictionModel(paper_spec()), d, o);
  for (const auto& s : n.starts)
    EXPECT_LE(s.evaluations, 80);
}

TEST(Identification, GammaRescaledOnlyWhenTheLevelsWouldLeaveTheirBounds) {
  SyntheticConfig c;
  c.seed = 12;
  c.duration_s = 8.0;
  const auto syn = make_synthetic(TsmFrictionModel(paper_spec()), c);
  const FitData d = prepare_fit_data(syn.recording);
  TsmFrictionModel same(paper_spec());
  EXPECT_EQ(adapt_scale_to_data(same, d), "");
  // Friction 100x smaller than the paper's: levels would need ~0.01.
  Recording small = syn.recording;
  for (std::size_t i = 0; i < small.size(); ++i)
    small.tau_in[i] = small.tau_out[i] + (small.tau_in[i] - small.tau_out[i]) * 0.01;
  const FitData ds = prepare_fit_data(small);
  TsmFrictionModel m(paper_spec());
  const auto before = simulate_friction(m, ds.motion);
  EXPECT_NE(adapt_scale_to_data(m, ds), "");
  const double scale = m.spec().gamma / 9.5651;
  EXPECT_NEAR(scale, 0.01, 0.005);
  // Only gamma changed: the start model's friction is scaled by c, exactly.
  EXPECT_EQ(m.spec().theta, paper_spec().theta);
  const auto after = simulate_friction(m, ds.motion);
  for (std::size_t i = 0; i < before.size(); i += 97)
    EXPECT_NEAR(after[i], scale * before[i], 1e-9 * (1.0 + std::fabs(before[i])));
}

TEST(Uncertainty, FlagsAParameterTheFrictionDoesNotDependOn) {
  SyntheticConfig c;
  c.seed = 13;
  c.duration_s = 20.0;
  const auto syn = make_synthetic(TsmFrictionModel(paper_spec()), c);
  const FitData d = prepare_fit_data(syn.recording);
  // kappa2 = 0 makes mu2 (1 - e^(-kappa2 |xdd|)) vanish: mu2 has no effect.
  TsmModelSpec s = paper_spec();
  s.terms[3].p[1] = 0.0;
  const auto u = estimate_uncertainty(TsmFrictionModel(s), d);
  bool mu2_flagged = false, kappa2_at_bound = false;
  for (const auto& w : u.warnings) {
    mu2_flagged |= w.find("acceleration_dependence.mu2: not identifiable") != std::string::npos;
    kappa2_at_bound |=
        w.find("acceleration_dependence.kappa2: at its lower bound") != std::string::npos;
  }
  EXPECT_TRUE(mu2_flagged);
  EXPECT_TRUE(kappa2_at_bound);
  for (const auto& p : u.parameters) {
    if (p.name == "coulomb.rho1") {
      EXPECT_TRUE(std::isfinite(p.std_error));
      EXPECT_LT(p.std_error, 0.05);
      EXPECT_TRUE(p.well_identified);
    }
    if (p.name == "core.gamma") {
      EXPECT_TRUE(p.fixed);
      EXPECT_TRUE(std::isnan(p.std_error));
    }
  }
  ASSERT_EQ(u.correlation.size(), u.free_names.size());
  for (std::size_t i = 0; i < u.correlation.size(); ++i)
    EXPECT_NEAR(u.correlation[i][i], 1.0, 1e-9);
  EXPECT_GE(u.correlation_time, 1.0);
  EXPECT_FALSE(u.notes.empty());  // why gamma is fixed
}

// --- the command line ---------------------------------------------------

struct Ran {
  int status;
  std::string output;
};

Ran run_tsm(const std::string& args) {
  const fs::path log =
      fs::temp_directory_path() / ("tsmh_fit_cli_" + std::to_string(::getpid()) + ".log");
  const std::string cmd = std::string(TSMH_TSM_BIN) + " " + args + " >" + log.string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  fs::remove(log);
  return {WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, ss.str()};
}

TEST(FitCommand, WritesParamsReportAndPlots) {
  const fs::path dir = fs::temp_directory_path() / ("tsmh_fit_cli_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  SyntheticConfig c;
  c.seed = 14;
  c.duration_s = 12.0;
  write_recording_csv(make_synthetic(TsmFrictionModel(paper_spec()), c).recording,
                      dir / "data.csv");
  // No --radius: the file's '# radius_m:' comment is used.
  const auto r =
      run_tsm("fit " + (dir / "data.csv").string() + " --output " + (dir / "p.yaml").string() +
              " --report " + (dir / "rep").string() + " --starts 2");
  ASSERT_EQ(r.status, 0) << r.output;
  EXPECT_NE(r.output.find("validation RMSE"), std::string::npos) << r.output;
  const auto model = load_model((dir / "p.yaml").string());
  EXPECT_EQ(model->kind(), "tsm");
  std::ifstream in(dir / "rep" / "report.json");
  const auto rep = nlohmann::json::parse(in);
  for (const char* k : {"rmse", "p2p", "fit_percent"})
    EXPECT_TRUE(rep["validation"][k].is_number()) << k;
  EXPECT_TRUE(rep["seconds"].is_number());
  EXPECT_EQ(rep["regimes"].size(), 13U);
  // Each regime as tsm gap reports it too: its scores, share and errors.
  for (const char* k : {"name", "group", "where", "rmse", "p2p", "fit_percent", "bias", "samples",
                        "concentration", "mean_error", "magnitude_excess"})
    EXPECT_TRUE(rep["regimes"][0].contains(k)) << k;
  EXPECT_FALSE(rep["parameters"].empty());
  EXPECT_EQ(rep["optimiser"]["method"], "lm");
  EXPECT_TRUE(rep["optimiser"]["library"].is_string());
  EXPECT_EQ(rep["data"]["derivatives"], "offline");
  for (const auto& p : rep["plots"])
    EXPECT_TRUE(fs::exists(dir / "rep" / p.get<std::string>())) << p;
  EXPECT_EQ(rep["plots"].size(), 3U) << rep["warnings"];
  // No staging directory is left behind.
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
  fs::remove_all(dir);
}

TEST(FitCommand, BadDataWritesNothing) {
  const fs::path dir =
      fs::temp_directory_path() / ("tsmh_fit_cli_bad_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    std::ofstream f(dir / "bad.csv");
    f << "t,x_in,tau_in,tau_out\n0,0,0,0\n0.001,nan,0,0\n";
  }
  const auto r = run_tsm("fit " + (dir / "bad.csv").string() + " --radius 0.01 --output " +
                         (dir / "p.yaml").string() + " --report " + (dir / "rep").string());
  EXPECT_NE(r.status, 0);
  EXPECT_NE(r.output.find("bad.csv:3"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "p.yaml"));
  EXPECT_FALSE(fs::exists(dir / "rep"));
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    (void)e;
    ++entries;
  }
  EXPECT_EQ(entries, 1U) << "only the input file";
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tsmh::estimator
