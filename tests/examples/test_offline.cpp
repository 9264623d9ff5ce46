// Offline runs: reproducibility, scenarios, effects, and the CLI's CSV.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <estimator/recording.hpp>
#include <estimator/table.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "virtual_tissue_slave/effects.hpp"
#include "virtual_tissue_slave/offline.hpp"

namespace vts = tsmh::virtual_tissue_slave;

namespace {

std::vector<vts::SlaveSample> run(const vts::OfflineOptions& o) {
  std::vector<vts::SlaveSample> out;
  vts::run_offline(vts::paper_slave(), o, [&](const vts::SlaveSample& s) { out.push_back(s); });
  return out;
}

int run_cli(const std::string& args) {
  const std::string cmd = std::string(VIRTUAL_SLAVE_BIN) + " " + args + " 2>/dev/null";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::filesystem::path temp_file(const std::string& name) {
  return std::filesystem::temp_directory_path() /
         ("vslave-test-" + std::to_string(::getpid()) + "-" + name);
}

}  // namespace

TEST(Offline, SameSeedSameData) {
  vts::OfflineOptions o;
  o.duration_s = 1.0;
  const auto a = run(o);
  const auto b = run(o);
  ASSERT_EQ(a.size(), 1000u);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].measured[0].T1, b[i].measured[0].T1);
    ASSERT_EQ(a[i].truth[1].x_out, b[i].truth[1].x_out);
  }
  o.seed = 2;
  const auto c = run(o);
  EXPECT_NE(a[500].measured[0].T1, c[500].measured[0].T1);
}

TEST(Offline, EveryScenarioRunsAndPalpateReachesTheInclusion) {
  for (const auto& name : vts::scenario_names()) {
    vts::OfflineOptions o;
    o.scenario = vts::make_scenario(name);
    o.duration_s = 10.0;
    double max_depth = 0.0;
    long n = 0;
    const auto stats = vts::run_offline(vts::paper_slave(), o, [&](const vts::SlaveSample& s) {
      max_depth = std::max(max_depth, s.truth[0].contact.indentation_m);
      ++n;
    });
    EXPECT_EQ(n, 10000) << name;
    EXPECT_EQ(stats.fallback_solves, 0) << name;
    if (name == "palpate") {
      const auto t = vts::tissue_truth(vts::tissue_preset("nodule"));
      EXPECT_GT(max_depth, 1.3 * t.inclusion_depth_m) << "the deep press should reach the nodule";
    }
    if (name == "chirp") {
      EXPECT_EQ(max_depth, 0.0) << "chirp is free motion";
    }
  }
  EXPECT_THROW(vts::make_scenario("waltz"), std::invalid_argument);
}

TEST(Offline, IdentifyIsFreeMotionThenPressesUnderLoad) {
  vts::OfflineOptions o;
  o.scenario = vts::make_scenario("identify");  // its own tissue: the nodule at 0.85 rad
  o.duration_s = o.scenario.default_duration_s;
  double depth_free = 0.0, depth_pressed = 0.0, load_pressed = 0.0;
  const auto stats = vts::run_offline(vts::paper_slave(), o, [&](const vts::SlaveSample& s) {
    const double d = s.truth[0].contact.indentation_m;
    if (s.t < 40.0) {
      depth_free = std::max(depth_free, d);
    } else {
      depth_pressed = std::max(depth_pressed, d);
      load_pressed = std::max(load_pressed, std::abs(s.truth[0].tau_out));
    }
  });
  EXPECT_EQ(stats.fallback_solves, 0);
  EXPECT_EQ(depth_free, 0.0) << "the first 40 s are free motion";
  const auto t = vts::tissue_truth(vts::tissue_preset("nodule"));
  EXPECT_GT(depth_pressed, 1.3 * t.inclusion_depth_m) << "the deep press reaches the nodule";
  EXPECT_GT(load_pressed, 0.1) << "N m at the tip: a load the fit can see";
  // Where free motion hands over to the presses the reference stays smooth:
  // no faster than excite's own top speed (2.3 rad/s); a seam would be a
  // step of tenths of a radian.
  double worst_step = 0.0;
  for (double tt = 39.0; tt < 42.0; tt += 1e-3)
    worst_step = std::max(
        worst_step, std::abs(o.scenario.reference(tt + 1e-3, 0) - o.scenario.reference(tt, 0)));
  EXPECT_LT(worst_step, 2.5e-3) << "rad per ms";
}

TEST(Offline, RerouteRaisesFrictionAtTheGivenTime) {
  vts::OfflineOptions o;
  o.duration_s = 12.0;
  o.tissue = vts::tissue_preset("none");
  o.reroute.at_s = 6.0;
  o.reroute.sheath1_wrap_rad = 5.0;
  double before = 0.0, after = 0.0;
  vts::run_offline(vts::paper_slave(), o, [&](const vts::SlaveSample& s) {
    const double f = std::abs(s.truth[0].friction);
    if (s.t < 6.0)
      before = std::max(before, f);
    else
      after = std::max(after, f);
  });
  EXPECT_GT(after, 1.3 * before);
}

TEST(Offline, EffectSpecsParseAndBadOnesAreNamed) {
  const auto e = vts::parse_effects({"viscous=0.5", "capstan=0", "position=0.2"});
  EXPECT_EQ(e.viscous, 0.5);
  EXPECT_FALSE(e.capstan);
  EXPECT_EQ(e.wrap_position_gain, 0.2);
  for (const char* bad : {"viscous", "viscous=-1", "capstan=2", "drag=1", "viscous=abc"}) {
    try {
      vts::parse_effects({bad});
      FAIL() << bad << " accepted";
    } catch (const std::invalid_argument& ex) {
      EXPECT_NE(std::string(ex.what()).find(bad), std::string::npos) << ex.what();
    }
  }
  const auto [a, b] = vts::parse_pair("3.5,1.2", "--wrap");
  EXPECT_EQ(a, 3.5);
  EXPECT_EQ(b, 1.2);
  EXPECT_TRUE(std::isnan(vts::parse_pair("4", "--wrap").second));
  EXPECT_THROW(vts::parse_pair("4,x", "--wrap"), std::invalid_argument);
}

TEST(OfflineCli, WritesTheCsvDataContract) {
  const auto path = temp_file("sine.csv");
  ASSERT_EQ(
      run_cli("--offline --scenario sine --duration 2 --joint 1 --exact-derivatives --output " +
              path.string()),
      0);
  const auto table = tsmh::estimator::read_csv_table(path);
  for (const char* col : {"t", "x_in", "tau_in", "tau_out", "x_out", "T1", "T3", "xd_in", "xdd_in"})
    EXPECT_TRUE(table.has(col)) << col;
  EXPECT_EQ(table.meta.at("radius_m"), "0.01");
  const auto rec = tsmh::estimator::read_recording_csv(path, std::nullopt, {true, true, true});
  ASSERT_EQ(rec.size(), 2000u);
  EXPECT_DOUBLE_EQ(rec.radius_m, 0.01);
  for (std::size_t i = 0; i < rec.size(); ++i)
    ASSERT_NEAR(rec.tau_in[i], 0.01 * (rec.T1[i] - rec.T3[i]), 1e-12);
  // Joint2's 0.4 Hz sine: x_in swings over most of +-0.8 rad within 2 s? At
  // least it moved, and friction makes tau_in differ from tau_out.
  double max_gap = 0.0;
  for (std::size_t i = 0; i < rec.size(); ++i)
    max_gap = std::max(max_gap, std::abs(rec.tau_in[i] - rec.tau_out[i]));
  EXPECT_GT(max_gap, 0.05);
  // The joint's name selects the same joint as its old 0-based index.
  const auto named = temp_file("sine-named.csv");
  ASSERT_EQ(run_cli("--offline --scenario sine --duration 2 --joint joint2 --exact-derivatives "
                    "--output " +
                    named.string()),
            0);
  EXPECT_EQ(tsmh::estimator::read_csv_table(named).column("x_in"), table.column("x_in"));
  std::filesystem::remove(named);
  std::filesystem::remove(path);
}

TEST(OfflineCli, BadOptionsFailWithoutWritingAnything) {
  const auto path = temp_file("bad.csv");
  EXPECT_NE(run_cli("--offline --scenario nope --output " + path.string()), 0);
  EXPECT_NE(run_cli("--offline --effect drag=1 --output " + path.string()), 0);
  EXPECT_NE(run_cli("--offline --joint 2 --output " + path.string()), 0);
  EXPECT_NE(run_cli("--offline --joint joint3 --output " + path.string()), 0);
  EXPECT_NE(run_cli("--offline --joint joint0 --output " + path.string()), 0);
  EXPECT_NE(run_cli("--offline --reroute-at 3 --output " + path.string()), 0);
  EXPECT_NE(run_cli("--offline"), 0);  // no --output
  EXPECT_FALSE(std::filesystem::exists(path));
}

TEST(OfflineCli, PrintsTheTissueTruth) {
  const auto path = temp_file("tissue.json");
  ASSERT_EQ(run_cli("--print-tissue --tissue nodule > " + path.string()), 0);
  std::ifstream in(path);
  std::string text, line;
  while (std::getline(in, line))
    text += line + "\n";
  EXPECT_NE(text.find("\"nm_per_rad\": 1.5"), std::string::npos) << text;
  std::filesystem::remove(path);
}
