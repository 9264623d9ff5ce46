// What the `tsm` command line tells its user: a typo named with the nearest
// valid word, one required input shown once in the help, warnings for header
// words it does not know and for times in milliseconds, simulate's error
// against a recorded tau_out, and verdicts in N m at the tip and on the master.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "estimator/fit_metrics.hpp"
#include "estimator/fit_workflow.hpp"
#include "estimator/model_gap.hpp"
#include "estimator/recording.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/table.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

class TsmCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("tsmh_tsm_cli_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// Runs tsm ARGS; returns the exit status, stdout and stderr in `output`.
  int tsm(const std::string& args, std::string& output) {
    const fs::path log = dir_ / "log";
    const std::string cmd = std::string(TSMH_TSM_BIN) + " " + args + " >" + log.string() + " 2>&1";
    const int rc = std::system(cmd.c_str());
    std::ifstream in(log);
    std::stringstream ss;
    ss << in.rdbuf();
    output = ss.str();
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  }

  std::string path(const char* name) const { return (dir_ / name).string(); }

  /// 4 s of the paper's model at 1 kHz, with tau_out.
  Recording synthetic() const {
    SyntheticConfig c;
    c.duration_s = 4.0;
    c.seed = 5;
    return make_synthetic(TsmFrictionModel(paper_spec()), c).recording;
  }

  fs::path dir_;
};

TEST_F(TsmCli, ASubcommandTypoIsNamedWithTheNearestOne) {
  std::string out;
  EXPECT_NE(tsm("fitt x", out), 0);
  EXPECT_NE(out.find("unknown subcommand 'fitt'; did you mean 'fit'?"), std::string::npos) << out;
  EXPECT_NE(tsm("smulate x", out), 0);
  EXPECT_NE(out.find("did you mean 'simulate'?"), std::string::npos) << out;
}

TEST_F(TsmCli, AnOptionTypoIsNamedWithTheNearestOne) {
  write_recording_csv(synthetic(), path("in.csv"));
  std::string out;
  EXPECT_NE(tsm("fit " + path("in.csv") + " --outptu " + path("p.yaml"), out), 0);
  EXPECT_NE(out.find("unknown option '--outptu'; did you mean --output?"), std::string::npos)
      << out;
  EXPECT_FALSE(fs::exists(path("p.yaml")));
  // Values of known options are not words to check: --params paper is fine.
  EXPECT_NE(tsm("simulate --params paper " + path("in.csv") + " --outptu=" + path("o.csv"), out),
            0);
  EXPECT_NE(out.find("did you mean --output?"), std::string::npos) << out;
}

TEST_F(TsmCli, SimulateHelpMarksNeitherFormOfTheInputRequired) {
  std::string out;
  ASSERT_EQ(tsm("simulate --help", out), 0) << out;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) {
    if (line.find("input") != std::string::npos && line.find("TEXT") != std::string::npos) {
      EXPECT_EQ(line.find("REQUIRED"), std::string::npos) << line;
    }
  }
  // Without either form, the error names the input.
  EXPECT_NE(tsm("simulate --params paper --output " + path("o.csv"), out), 0);
  EXPECT_NE(out.find("input CSV"), std::string::npos) << out;
}

TEST_F(TsmCli, SimulateReportsItsErrorAgainstTauOut) {
  const Recording rec = synthetic();
  write_recording_csv(rec, path("in.csv"));
  std::string out;
  ASSERT_EQ(tsm("simulate --params paper " + path("in.csv") + " --output " + path("o.csv"), out), 0)
      << out;
  const Table sim = read_csv_table(path("o.csv"));
  const Recording back = read_recording_csv(path("in.csv"));
  const auto& est = sim.column("tau_out_est");
  const auto e = error_metrics(back.tau_out, est, [](std::size_t) { return true; });
  char want[96];
  std::snprintf(want, sizeof want, "RMSE %.4g N m, p2p %.4g N m", e.rmse, e.p2p);
  EXPECT_NE(out.find(want), std::string::npos) << want << "\n" << out;
  EXPECT_NE(out.find("the naive feedback (tau_in) vs tau_out"), std::string::npos) << out;
}

TEST_F(TsmCli, AHeaderTypoIsWarnedWithTheColumnMeant) {
  Recording rec = synthetic();
  Table t = recording_to_table(rec);
  for (auto& n : t.names)
    if (n == "tau_in") n = "tauin";
  write_csv_table(t, path("in.csv"));
  std::string out;
  ASSERT_EQ(tsm("simulate --params paper " + path("in.csv") + " --output " + path("o.csv"), out), 0)
      << out;
  EXPECT_NE(out.find("column 'tauin' is not a column of the CSV contract; did you mean tau_in?"),
            std::string::npos)
      << out;
  // A required column misspelt is an error naming the word it found.
  for (auto& n : t.names)
    if (n == "t") n = "time";
  write_csv_table(t, path("in2.csv"));
  EXPECT_NE(tsm("simulate --params paper " + path("in2.csv") + " --output " + path("o2.csv"), out),
            0);
  EXPECT_NE(out.find("the header has 'time': did you mean t?"), std::string::npos) << out;
}

TEST_F(TsmCli, TimesInMillisecondsAreWarnedAbout) {
  Recording rec = synthetic();
  for (auto& t : rec.t)
    t *= 1000.0;
  write_recording_csv(rec, path("ms.csv"));
  std::string out;
  tsm("fit " + path("ms.csv") + " --output " + path("p.yaml"), out);
  EXPECT_NE(out.find("the t column looks like milliseconds"), std::string::npos) << out;
  // Seconds: no such warning.
  write_recording_csv(synthetic(), path("s.csv"));
  ASSERT_EQ(tsm("simulate --params paper " + path("s.csv") + " --output " + path("o.csv"), out), 0);
  EXPECT_EQ(out.find("milliseconds"), std::string::npos) << out;
}

// --- the verdict layer ------------------------------------------------------

TEST(Verdicts, TheErrorIsGivenAtTheTipAndOnTheMaster) {
  FitVerdict v;
  explain_for_haptics(v, 0.5, 0.01, nullptr);  // 0.5 N of friction, a 10 mm pulley
  EXPECT_NEAR(v.tip_rmse_nm, 0.005, 1e-12);
  EXPECT_NE(v.meaning.find("0.005 N m RMS"), std::string::npos) << v.meaning;
  EXPECT_NE(v.meaning.find("--force-scale"), std::string::npos) << v.meaning;
  MasterScale m{0.6, 0.3, "test"};
  explain_for_haptics(v, 0.5, 0.01, &m);
  EXPECT_NEAR(v.master_rmse_nm, 0.003, 1e-12);
  EXPECT_NEAR(v.master_fraction, 0.01, 1e-12);
  // 1 % of the peak is under the ~10 % a hand tells apart above 10 % of it.
  EXPECT_NE(v.meaning.find("1 % of its peak torque 0.3 N m"), std::string::npos) << v.meaning;
  EXPECT_NE(v.meaning.find("above 0.03 N m (10 % of the peak)"), std::string::npos) << v.meaning;
}

TEST(Verdicts, GradedBeyondFair) {
  ErrorMetrics train, val;
  train.rmse = 1.1;
  val.rmse = 1.15;
  val.fit_percent = 95;
  EXPECT_EQ(judge_fit(train, val, 1.0).grade, "good");
  val.rmse = train.rmse = 2.5;
  EXPECT_EQ(judge_fit(train, val, 1.0).grade, "fair");
  val.rmse = train.rmse = 11.5;  // the demo's figure: 11.5x the noise floor
  const FitVerdict v = judge_fit(train, val, 1.0);
  EXPECT_EQ(v.grade, "coarse") << v.reason;
  EXPECT_NE(v.reason.find("fair <= 3"), std::string::npos) << v.reason;
  val.fit_percent = 40;
  EXPECT_EQ(judge_fit(train, val, 1.0).grade, "poor");
}

TEST(Verdicts, ABoundIsReportedOneWayWithItsConsequence) {
  ParameterEstimate mu1;
  mu1.name = "stribeck.mu1";
  mu1.value = 20.0;
  mu1.lower = 0.0;
  mu1.upper = 20.0;
  mu1.at_bound = true;
  EXPECT_EQ(at_bound_text(mu1), "at its upper bound (value 20, bound 20)");
  const std::string c = bound_consequence(mu1);
  EXPECT_NE(c.find("likely absent"), std::string::npos) << c;
  EXPECT_NE(c.find("drop 'stribeck'"), std::string::npos) << c;
  ParameterEstimate mu3 = mu1;
  mu3.name = "acceleration_dependence.mu3";
  mu3.value = 0.009286;
  EXPECT_EQ(at_bound_text(mu3), "at its lower bound (value 0.009286, bound 0)");
  EXPECT_NE(bound_consequence(mu3).find("adds no friction"), std::string::npos);
  // The fit verdict names it with the same words.
  UncertaintyReport u;
  u.parameters = {mu1};
  ErrorMetrics train, val;
  train.rmse = val.rmse = 1.0;
  val.fit_percent = 95;
  const FitVerdict v = judge_fit(train, val, 1.0, &u);
  EXPECT_NE(v.reason.find("stribeck.mu1 at its upper bound (value 20, bound 20): the Stribeck"),
            std::string::npos)
      << v.reason;
}

TEST(Verdicts, AFlatShapeIsNotPlotted) {
  EXPECT_TRUE(shape_is_flat({{0.0, 0.0}, {1.0, 0.0}, {2.0, -0.0}}));
  EXPECT_FALSE(shape_is_flat({{0.0, 0.0}, {1.0, 0.01}}));
}

}  // namespace
}  // namespace tsmh::estimator
