// The contract of `tsm simulate` on a recording without xd_in/xdd_in: it runs
// exactly the causal estimator haptic-server runs (DistalTorqueEstimator with
// its default differentiator), sample by sample, never a smoother.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "estimator/distal_estimator.hpp"
#include "estimator/estimator_settings.hpp"
#include "estimator/recording.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/table.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

TEST(SimulateCommand, WithoutDerivativesRunsTheServersEstimatorSampleBySample) {
  const fs::path dir = fs::temp_directory_path() / ("tsmh_sim_cli_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  SyntheticConfig c;
  c.motion = MotionKind::kSurgeon;
  c.duration_s = 8.0;
  c.jitter_s = 2e-4;       // uneven time stamps
  c.drop_fraction = 0.02;  // and lost samples
  c.seed = 3;
  write_recording_csv(make_synthetic(TsmFrictionModel(paper_spec()), c).recording, dir / "in.csv");
  const std::string cmd = std::string(TSMH_TSM_BIN) + " simulate --params paper --input " +
                          (dir / "in.csv").string() + " --output " + (dir / "out.csv").string() +
                          " >" + (dir / "log").string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 0);

  // What the server computes from the same samples (as read back from the
  // file, so both see identical numbers).
  const Recording rec = read_recording_csv(dir / "in.csv");
  DistalTorqueEstimator server(std::make_unique<TsmFrictionModel>(paper_spec()), rec.radius_m);
  const Table out = read_csv_table(dir / "out.csv");
  const auto& f = out.column("F");
  const auto& est = out.column("tau_out_est");
  ASSERT_EQ(f.size(), rec.size());
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const Estimate e = server.update(rec.t[i], rec.x_in[i], rec.tau_in[i]);
    ASSERT_EQ(f[i], e.friction) << "row " << i;
    ASSERT_EQ(est[i], e.tau_out_est) << "row " << i;
  }
  // The input file may also be given as a positional argument, as fit, gap
  // and convert take it; --input stays as an alias.
  const std::string positional =
      std::string(TSMH_TSM_BIN) + " simulate --params paper " + (dir / "in.csv").string() +
      " --output " + (dir / "out2.csv").string() + " >" + (dir / "log2").string() + " 2>&1";
  const int rc2 = std::system(positional.c_str());
  ASSERT_TRUE(WIFEXITED(rc2) && WEXITSTATUS(rc2) == 0);
  EXPECT_EQ(read_csv_table(dir / "out2.csv").column("F"), f);
  fs::remove_all(dir);
}

// The estimator's numeric settings are read by one table (estimator_settings):
// `tsm simulate` refuses a value out of range, or not a number, with the same
// words haptic-server's configuration uses for the same setting, and a value
// at a boundary the server accepts is accepted here too.
TEST(SimulateCommand, EstimatorFlagsShareTheServersLimitsAndWords) {
  const fs::path dir = fs::temp_directory_path() / ("tsmh_sim_flags_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  SyntheticConfig c;
  c.duration_s = 0.5;
  write_recording_csv(make_synthetic(TsmFrictionModel(paper_spec()), c).recording, dir / "in.csv");
  const auto run = [&](const std::string& flag, const std::string& value) {
    const std::string cmd = std::string(TSMH_TSM_BIN) + " simulate --params paper " +
                            (dir / "in.csv").string() + " --output " + (dir / "out.csv").string() +
                            " --derivatives differentiator " + flag + " " + value + " >" +
                            (dir / "log").string() + " 2>&1";
    const int rc = std::system(cmd.c_str());
    std::ifstream in(dir / "log");
    std::stringstream text;
    text << in.rdbuf();
    return std::make_pair(WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, text.str());
  };
  for (const auto& s : numeric_settings()) {
    const std::string flag(s.flag);
    for (const double bad : {s.hi * 2.0, -1.0}) {
      std::ostringstream value;
      value << bad;
      const auto [rc, log] = run(flag, value.str());
      EXPECT_NE(rc, 0) << flag << ' ' << bad;
      EXPECT_NE(log.find(s.problem(bad)), std::string::npos) << flag << ' ' << bad << ": " << log;
    }
    const auto [rc_nan, log_nan] = run(flag, "nan");
    EXPECT_NE(rc_nan, 0) << flag << " nan: " << log_nan;
    std::ostringstream hi;
    hi << s.hi;
    const auto [rc_hi, log_hi] = run(flag, hi.str());
    EXPECT_EQ(rc_hi, 0) << flag << ' ' << s.hi << ": " << log_hi;
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tsmh::estimator
