// Free-motion identification: `tsm fit --free-motion` without a
// tip sensor, the distal torque from the joint's dynamics, and the refusal of
// data that shows contact.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "estimator/distal_estimator.hpp"
#include "estimator/fit_workflow.hpp"
#include "estimator/free_motion.hpp"
#include "estimator/model_io.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/table.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

// The deployed causal estimator with `model` on `rec`: RMSE of its distal
// torque against rec.tau_out over t >= 0.5 s.
double deployed_rmse(const FrictionModel& model, const Recording& rec) {
  DistalTorqueEstimator est(model.clone(), rec.radius_m);
  double ss = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const Estimate e = est.update(rec.t[i], rec.x_in[i], rec.tau_in[i]);
    if (rec.t[i] < rec.t.front() + 0.5) continue;
    ss += (e.tau_out_est - rec.tau_out[i]) * (e.tau_out_est - rec.tau_out[i]);
    ++n;
  }
  return std::sqrt(ss / static_cast<double>(n));
}

// A joint swept back and forth at `amp` rad, 0.5 Hz, whose proximal torque is
// a friction band +-band (sign of the velocity) plus `tissue` N m/rad beyond
// x_in = `surface` (one-sided, as a contact).
Recording swept(double band, double tissue, double surface, double amp = 0.8) {
  Recording r;
  r.source = "swept";
  r.radius_m = 0.01;
  const double w = 2.0 * std::numbers::pi * 0.5;
  for (int i = 0; i < 20000; ++i) {
    const double t = i * 1e-3;
    const double x = amp * std::sin(w * t);
    const double xd = amp * w * std::cos(w * t);
    r.t.push_back(t);
    r.x_in.push_back(x);
    r.x_out.push_back(x);
    r.tau_in.push_back((xd >= 0 ? band : -band) + (x > surface ? tissue * (x - surface) : 0.0));
  }
  return r;
}

TEST(FreeMotion, ParametersFromFreeMotionAloneEstimateLoadedDataWithin1p2OfATauOutFit) {
  const TsmFrictionModel truth(paper_spec());
  SyntheticConfig free_cfg;
  free_cfg.load_amplitude = 0.0;  // nothing at the tip: free motion
  free_cfg.seed = 21;
  SyntheticData free = make_synthetic(truth, free_cfg);
  SyntheticConfig loaded_cfg;  // a slow random distal load (+-0.06 N m): the "palpation"
  loaded_cfg.seed = 22;
  const SyntheticData loaded = make_synthetic(truth, loaded_cfg);

  // Reference: the usual fit, with the measured tau_out.
  const auto start = load_model("paper");
  const FitRun with_tau = run_fit(free.recording, *start, "paper");
  // Free motion: no tau_out column at all.
  Recording no_tau = free.recording;
  no_tau.tau_out.clear();
  const FreeMotionData fm = free_motion_recording(no_tau);
  EXPECT_EQ(fm.distal_source, "zero");
  const FitRun without_tau = run_fit(fm.recording, *start, "paper");

  const double ref = deployed_rmse(*with_tau.fit.model, loaded.recording);
  const double fm_rmse = deployed_rmse(*without_tau.fit.model, loaded.recording);
  double naive = 0.0;  // feeding tau_in back as the distal torque
  for (std::size_t i = 0; i < loaded.recording.size(); ++i)
    naive += std::pow(loaded.recording.tau_in[i] - loaded.recording.tau_out[i], 2);
  naive = std::sqrt(naive / static_cast<double>(loaded.recording.size()));
  EXPECT_LE(fm_rmse, 1.2 * ref) << "free-motion " << fm_rmse << " vs tau_out fit " << ref;
  EXPECT_LT(fm_rmse, 0.2 * naive) << "naive " << naive;
}

TEST(FreeMotion, LoadedSyntheticDataIsRefusedAsContact) {
  SyntheticConfig c;
  c.seed = 22;
  c.load_amplitude = 0.06;
  Recording rec = make_synthetic(TsmFrictionModel(paper_spec()), c).recording;
  rec.tau_out.clear();
  try {
    free_motion_recording(rec);
    FAIL() << "contact not detected";
  } catch (const DataError& e) {
    EXPECT_EQ(e.column(), "tau_in");
    EXPECT_NE(std::string(e.what()).find("shows contact"), std::string::npos) << e.what();
  }
}

TEST(FreeMotion, ContactCheckSeesATissueLoadBeyondTheSurfaceButNotAFreeBand) {
  const ContactCheckConfig cfg;
  for (const double tissue : {0.0, 0.2}) {
    const Recording r = swept(0.1, tissue, 0.4);
    std::vector<double> xd(r.size());
    for (std::size_t i = 0; i < r.size(); ++i)
      xd[i] = 0.8 * std::numbers::pi * std::cos(std::numbers::pi * r.t[i]);
    const ContactCheck c = check_contact(r.t, r.x_in, xd, r.tau_in, cfg);
    std::string why;
    EXPECT_EQ(shows_contact(c, cfg, &why), tissue > 0.0) << "tissue " << tissue << ": " << why;
    EXPECT_NEAR(c.band_half_width_nm, 0.1, 1e-9);
    EXPECT_EQ(why.empty(), tissue == 0.0);
  }
}

TEST(FreeMotion, DistalTorqueFromJointInertiaAndDampingWhenTheEncoderExists) {
  Recording r = swept(0.1, 0.0, 0.0);
  FreeMotionConfig cfg;
  cfg.joint_inertia = 5e-3;  // large enough that J xdd is well above the encoder's noise
  cfg.joint_damping = 2e-2;
  const FreeMotionData fm = free_motion_recording(r, cfg);
  EXPECT_EQ(fm.distal_source, "inertia_damping");
  const double w = std::numbers::pi;
  double worst = 0.0, peak = 0.0;
  for (std::size_t i = 500; i + 500 < r.size(); ++i) {
    const double t = r.t[i];
    const double expect =
        5e-3 * (-0.8 * w * w * std::sin(w * t)) + 2e-2 * 0.8 * w * std::cos(w * t);
    worst = std::max(worst, std::fabs(fm.recording.tau_out[i] - expect));
    peak = std::max(peak, std::fabs(expect));
  }
  EXPECT_LT(worst, 0.05 * peak) << "peak " << peak;

  // No encoder (a joint without one reads NaN): zero, and the notes say why.
  r.x_out.assign(r.size(), std::nan(""));
  const FreeMotionData zero = free_motion_recording(r, cfg);
  EXPECT_EQ(zero.distal_source, "zero");
  ASSERT_FALSE(zero.notes.empty());
  EXPECT_NE(zero.notes.back().find("no joint encoder"), std::string::npos) << zero.notes.back();
  for (double v : zero.recording.tau_out)
    ASSERT_EQ(v, 0.0);
}

TEST(FreeMotion, BadInputIsRefusedNamingTheColumn) {
  Recording r = swept(0.1, 0.0, 0.0);
  r.x_out[1234] = std::nan("");
  try {
    free_motion_recording(r);
    FAIL();
  } catch (const DataError& e) {
    EXPECT_EQ(e.column(), "x_out");
    EXPECT_NE(std::string(e.what()).find("sample 1235"), std::string::npos) << e.what();
  }
  Recording no_tau_in = swept(0.1, 0.0, 0.0);
  no_tau_in.tau_in.clear();
  EXPECT_THROW(free_motion_recording(no_tau_in), DataError);
  // Strokes shorter than the friction's transition: nothing to judge contact by.
  EXPECT_THROW(free_motion_recording(swept(0.1, 0.0, 0.0, 0.1)), DataError);
  FreeMotionConfig negative;
  negative.joint_inertia = -1.0;
  EXPECT_THROW(free_motion_recording(swept(0.1, 0.0, 0.0), negative), DataError);
}

TEST(FreeMotion, CliFitsWithoutTauOutOnlyWhenToldAndReportsIt) {
  const fs::path dir = fs::temp_directory_path() / ("tsmh_fm_cli_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  SyntheticConfig c;
  c.load_amplitude = 0.0;
  c.seed = 23;
  Recording rec = make_synthetic(TsmFrictionModel(paper_spec()), c).recording;
  rec.tau_out.clear();
  write_recording_csv(rec, dir / "free.csv");
  const auto run = [&](const std::string& args) {
    const std::string cmd =
        std::string(TSMH_TSM_BIN) + " " + args + " >" + (dir / "log").string() + " 2>&1";
    const int rc = std::system(cmd.c_str());
    std::ifstream log(dir / "log");
    std::stringstream text;
    text << log.rdbuf();
    return std::pair{WIFEXITED(rc) ? WEXITSTATUS(rc) : -1, text.str()};
  };
  const std::string data = (dir / "free.csv").string();
  const auto refused = run("fit " + data + " --output " + (dir / "a.yaml").string());
  EXPECT_NE(refused.first, 0);
  EXPECT_NE(refused.second.find("tau_out"), std::string::npos) << refused.second;
  EXPECT_FALSE(fs::exists(dir / "a.yaml"));

  const auto ok = run("fit " + data + " --free-motion --output " + (dir / "b.yaml").string() +
                      " --report " + (dir / "rep").string());
  ASSERT_EQ(ok.first, 0) << ok.second;
  EXPECT_NE(ok.second.find("distal torque taken as zero"), std::string::npos) << ok.second;
  std::ifstream report(dir / "rep" / "report.json");
  std::stringstream json;
  json << report.rdbuf();
  EXPECT_NE(json.str().find("\"free_motion\""), std::string::npos);

  const auto gap =
      run("gap " + data + " --free-motion --max-effects 0 --output " + (dir / "gap").string());
  EXPECT_EQ(gap.first, 0) << gap.second;
  EXPECT_TRUE(fs::exists(dir / "gap" / "params.yaml"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tsmh::estimator
