// The model-gap workflow (`tsm gap`) on data in which an effect is
// hidden: the paper's model with a term injected (synthetic.hpp) and the
// virtual slave run offline with its hidden-effect switches. Each effect must
// be named, and the validation gap must close: shrink by >= 40 %, or come
// down to the floor, estimated as the gap the base model leaves on the same
// world with the effect switched off (same motion, same noise), x 1.15.
// docs/model-gap.md gives the numbers. Seeds 111-117 were not used while
// developing the workflow; the noise-floor checks (final gap within 1.2x the floor estimated from
// the data), a flexible form (seed 119) and the palpation confound.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "estimator/fit_workflow.hpp"
#include "estimator/model_gap.hpp"
#include "estimator/model_io.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

constexpr double kFloorTolerance = 1.15;
constexpr double kRequiredShrink = 0.40;

struct Injected {
  TermKind kind;
  std::vector<double> p;
};

Recording paper_world(std::uint64_t seed, const std::vector<Injected>& hidden) {
  TsmModelSpec s = paper_spec();
  for (const auto& h : hidden) {
    Term& t = s.add(h.kind);
    for (std::size_t k = 0; k < h.p.size(); ++k)
      t.p[k] = h.p[k];
  }
  SyntheticConfig c;
  c.seed = seed;
  return make_synthetic(TsmFrictionModel(s), c).recording;
}

GapResult gap(const Recording& rec, const std::string& base = "paper") {
  return find_model_gaps(rec, *load_model(base), base);
}

// The level terms only, without the structural candidates (distributed
// slip and its copies): the virtual slave's sheath is a chain of segments
// that slip one after the other, pulled by two tendons, so with them on the
// workflow names the chain's distributed slip and the tendons' tension
// first, and the elements' sliding functions (Coulomb, Stribeck, viscous)
// take a switched-on drag with them. The tests of the slave's switchable
// effects are about those level effects.
GapResult level_gap(const Recording& rec, const std::string& base) {
  GapOptions o;
  for (const auto& info : term_catalog()) {
    const std::string name(info.name);
    // The |tau_in| / R forms stay off, as by default (docs/model-gap.md).
    if (info.kind == TermKind::kCoulomb || name == "load_dependent" || name == "load_saturating")
      continue;
    o.candidates.push_back(name);
  }
  return find_model_gaps(rec, *load_model(base), base, o);
}

// The floor: the base model's validation gap on the world without the effect.
double floor_of(const Recording& control, const std::string& base = "paper") {
  return run_fit(control, *load_model(base), base).validation.rmse;
}

std::vector<std::string> names(const GapResult& g) {
  std::vector<std::string> n;
  for (const auto& e : g.effects)
    n.push_back(e.name);
  return n;
}

void record(const GapResult& g, double floor) {
  ::testing::Test::RecordProperty("gap_base_rmse", std::to_string(g.gap_base.rmse));
  ::testing::Test::RecordProperty("gap_final_rmse", std::to_string(g.gap_final.rmse));
  ::testing::Test::RecordProperty("floor_rmse", std::to_string(floor));
  ::testing::Test::RecordProperty("noise_floor", std::to_string(g.noise));
  std::string found;
  for (const auto& e : g.effects)
    found += e.name + " ";
  ::testing::Test::RecordProperty("effects", found);
  ::testing::Test::RecordProperty("seconds", std::to_string(g.seconds));
}

// With the base at the noise floor, the final gap within 1.2x the
// floor estimated from the data itself.
void expect_at_noise_floor(const GapResult& g) {
  EXPECT_LE(g.gap_final.rmse, 1.2 * g.noise)
      << "gap " << g.gap_base.rmse << " -> " << g.gap_final.rmse << " N, noise floor " << g.noise;
}

void expect_closed(const GapResult& g, double floor) {
  const bool shrunk = g.gap_final.rmse <= (1.0 - kRequiredShrink) * g.gap_base.rmse;
  const bool at_floor = g.gap_final.rmse <= kFloorTolerance * floor;
  EXPECT_TRUE(shrunk || at_floor) << "gap " << g.gap_base.rmse << " -> " << g.gap_final.rmse
                                  << " N, floor " << floor << " N";
}

// --- the paper's model with a term injected ------------------------------

TEST(GapPaperWorld, NothingHiddenNothingFound) {
  const auto g = gap(paper_world(111, {}));
  record(g, g.gap_base.rmse);
  EXPECT_TRUE(g.effects.empty()) << ::testing::PrintToString(names(g));
  EXPECT_EQ(g.gap_final.rmse, g.gap_base.rmse);
  // Either the base is already at the noise floor (nothing left
  // to explain, no round needed) or no candidate comes near the margin.
  if (g.rounds.empty()) {
    EXPECT_LE(g.gap_base.rmse, 1.03 * g.noise) << g.stop_reason;
  } else {
    for (const auto& t : g.rounds.front().trials)
      EXPECT_LT(t.gain, 0.05) << t.name;  // far below the 10 % margin
  }
}

TEST(GapPaperWorld, HiddenViscousDrag) {
  const auto g = gap(paper_world(112, {{TermKind::kViscous, {0.3}}}));
  const double floor = floor_of(paper_world(112, {}));
  record(g, floor);
  EXPECT_EQ(names(g), std::vector<std::string>{"viscous"});
  expect_closed(g, floor);
  expect_at_noise_floor(g);
}

TEST(GapPaperWorld, HiddenLoadDependence) {
  const auto g = gap(paper_world(113, {{TermKind::kLoadDependent, {0.03}}}));
  const double floor = floor_of(paper_world(113, {}));
  record(g, floor);
  EXPECT_EQ(names(g), std::vector<std::string>{"load_dependent"});
  expect_closed(g, floor);
  expect_at_noise_floor(g);
}

TEST(GapPaperWorld, HiddenPositionDependence) {
  const auto g = gap(paper_world(114, {{TermKind::kPositionDependent, {0.25, 0.2}}}));
  const double floor = floor_of(paper_world(114, {}));
  record(g, floor);
  EXPECT_EQ(names(g), std::vector<std::string>{"position_dependent"});
  expect_closed(g, floor);
  expect_at_noise_floor(g);
}

TEST(GapPaperWorld, HiddenStepInTime) {
  // The sheath re-routed at t = 22 s: every sliding level up by 0.2.
  const auto g = gap(paper_world(115, {{TermKind::kTimeVarying, {0.0, 0.2, 22.0, 0.0}}}));
  const double floor = floor_of(paper_world(115, {}));
  record(g, floor);
  ASSERT_EQ(names(g), std::vector<std::string>{"time_varying"});
  for (const auto& [name, value] : g.effects.front().parameters) {
    if (name == "time_varying.t_step") {
      EXPECT_NEAR(value, 22.0, 0.5);
    }
  }
  expect_closed(g, floor);
  expect_at_noise_floor(g);
}

TEST(GapPaperWorld, TwoHiddenEffectsAreBothNamed) {
  const auto g = gap(paper_world(
      116, {{TermKind::kLoadDependent, {0.03}}, {TermKind::kPositionDependent, {0.25, 0.2}}}));
  const double floor = floor_of(paper_world(116, {}));
  record(g, floor);
  const auto n = names(g);
  EXPECT_EQ(std::set<std::string>(n.begin(), n.end()),
            (std::set<std::string>{"load_dependent", "position_dependent"}));
  expect_closed(g, floor);
  // The hidden load is c_load |tau_in| / R, a form tsm gap tries only by
  // name (it contains the friction itself); load_scaling on the distal load
  // expresses it through k_along to within 1.3x the noise floor here
  // (1.25x), not 1.2x.
  EXPECT_LE(g.gap_final.rmse, 1.3 * g.noise)
      << "gap " << g.gap_base.rmse << " -> " << g.gap_final.rmse << " N, noise floor " << g.noise;
}

TEST(GapPaperWorld, DahlBaseRediscoversThePaperEffects) {
  const auto g = gap(paper_world(117, {}), "dahl");
  record(g, 0.0);
  // distributed_slip counts: its sliding functions are a Coulomb level per
  // direction and a Stribeck rise, and its elements shape the transition
  // after a reversal that Dahl's single n = 1 state gets wrong (the paper's
  // n = 2 and lambda).
  const std::set<std::string> paper_effects = {"direction_asymmetry", "stribeck",
                                               "acceleration_dependence", "reversal_offset",
                                               "distributed_slip"};
  const auto n = names(g);
  EXPECT_GE(n.size(), 2U);
  for (const auto& e : n)
    EXPECT_TRUE(paper_effects.count(e)) << e << " is not one of the paper's effects";
  EXPECT_LT(g.gap_final.rmse, 0.8 * g.gap_base.rmse);
}

TEST(GapPaperWorld, RippleAlongTheStrokeIsNamedWithItsShape) {
  // Not the quadratic form of position_dependent: a ripple, 3 periods over
  // the stroke. The flexible candidates name it and close the gap.
  const auto g = gap(paper_world(119, {{TermKind::kPositionRipple, {0.08, 0.0, 9.4}}}));
  record(g, g.noise);
  ASSERT_EQ(names(g), std::vector<std::string>{"position_dependent"});
  EXPECT_EQ(g.effects.front().form, "position_ripple");
  EXPECT_EQ(g.effects.front().variable, "x");
  EXPECT_GT(g.effects.front().shape.size(), 100U);
  EXPECT_TRUE(g.confounds.empty());
  expect_at_noise_floor(g);
}

// --- the virtual slave with its hidden-effect switches ---------------------

Recording virtual_slave(const std::string& name, const std::string& args) {
  const fs::path out = fs::temp_directory_path() / ("tsmh_gap_vs_" + name + ".csv");
  const std::string cmd = std::string(TSMH_VIRTUAL_SLAVE) +
                          " --offline --duration 40 --scenario multisine --seed 7 --output " +
                          out.string() + " " + args + " >/dev/null 2>&1";
  if (std::system(cmd.c_str()) != 0) throw std::runtime_error("virtual-slave failed: " + cmd);
  Recording r = read_recording_csv(out);
  fs::remove(out);
  return r;
}

// Two sessions in one recording (a gap of 2 s between them, which the CSV
// contract allows): the second starts where the first ended.
Recording concatenate(Recording a, const Recording& b) {
  const double shift = a.t.back() + 2.0 - b.t.front();
  for (std::size_t i = 0; i < b.size(); ++i) {
    a.t.push_back(b.t[i] + shift);
    a.x_in.push_back(b.x_in[i]);
    a.tau_in.push_back(b.tau_in[i]);
    a.tau_out.push_back(b.tau_out[i]);
  }
  a.x_out.clear();
  a.T1.clear();
  a.T3.clear();
  return a;
}

// The virtual slave's sheath is a chain of stick-slip segments: its
// hysteresis has memory, which the paper's single state lacks, so tsm gap
// names hysteresis_elements on any of its recordings (HysteresisMemoryOfTheChain).
// The tests of the switchable hidden effects start from the class that has it.
constexpr const char* kChainBase = "paper_memory";

TEST(GapVirtualSlave, HysteresisMemoryOfTheChain) {
  const auto g = gap(virtual_slave("memory", "--effect capstan=0"));
  record(g, g.gap_base.rmse);
  ASSERT_FALSE(g.effects.empty());
  // Either form of the memory: two parallel hysteresis states, or the
  // elasto-slide elements of distributed slip (its segments slip one after
  // the other), which the workflow may put in place of the paper's state.
  EXPECT_TRUE(g.effects.front().name == "hysteresis_elements" ||
              g.effects.front().name == "distributed_slip")
      << g.effects.front().name;
  EXPECT_LT(g.gap_final.rmse, 0.8 * g.gap_base.rmse);
}

TEST(GapVirtualSlave, NothingHiddenNothingFound) {
  // The plant's load dependence (capstan) switched off: the paper's model
  // with memory describes the rest without a missing term.
  const auto g = level_gap(virtual_slave("none", "--effect capstan=0"), kChainBase);
  record(g, g.gap_base.rmse);
  EXPECT_TRUE(g.effects.empty()) << ::testing::PrintToString(names(g));
}

TEST(GapVirtualSlave, HiddenViscousDrag) {
  // Without the controller's backlash compensation the motor moves smoothly
  // (the compensation's dead-zone jumps reach 9 rad/s, where the plant's
  // node drag no longer looks like a sliding-level term).
  const std::string plain = "--no-compensation --effect capstan=0";
  const auto g = level_gap(virtual_slave("visc", plain + " --effect viscous=2"), kChainBase);
  const double floor = floor_of(virtual_slave("visc_ctl", plain), kChainBase);
  record(g, floor);
  EXPECT_EQ(names(g), std::vector<std::string>{"viscous"});
  expect_closed(g, floor);
}

TEST(GapVirtualSlave, HiddenPositionDependence) {
  const auto g =
      level_gap(virtual_slave("pos", "--effect capstan=0 --effect position=0.3"), kChainBase);
  const double floor = floor_of(virtual_slave("pos_ctl", "--effect capstan=0"), kChainBase);
  record(g, floor);
  EXPECT_EQ(names(g), std::vector<std::string>{"position_dependent"});
  expect_closed(g, floor);
}

TEST(GapVirtualSlave, SheathReroutedMidRun) {
  const auto g = level_gap(
      virtual_slave("time", "--effect capstan=0 --reroute-at 20 --reroute-wrap 4.5"), "paper");
  const double floor = floor_of(virtual_slave("time_ctl", "--effect capstan=0"));
  record(g, floor);
  ASSERT_EQ(names(g), std::vector<std::string>{"time_varying"});
  for (const auto& [name, value] : g.effects.front().parameters) {
    if (name == "time_varying.t_step") {
      EXPECT_NEAR(value, 20.0, 0.5);
    }
  }
  expect_closed(g, floor);
}

TEST(GapVirtualSlave, LoadDependenceOfTheCapstanEffect) {
  // In one contact session the load is a function of the angle (a tissue
  // spring, and the transmission's compliance), so load and position
  // dependence explain the same residual. Two sessions, free motion then
  // hard tissue, give the same angles with different loads.
  const auto session = [](const std::string& name, const std::string& args) {
    return virtual_slave(name, args);
  };
  const auto with = concatenate(session("l_free", "--tissue none"),
                                session("l_hard", "--tissue hard --surface 0.3"));
  const auto without =
      concatenate(session("l_free0", "--tissue none --effect capstan=0"),
                  session("l_hard0", "--tissue hard --surface 0.3 --effect capstan=0"));
  const auto g = level_gap(with, "paper");
  const double floor = floor_of(without);
  record(g, floor);
  // One contact position: with flexible position forms (a bump where the
  // tissue is) position can imitate the load here. Never one
  // confident wrong name. Either load_dependent is named, or the effect
  // named is reported as confounded with load_dependent.
  // After the load, the chain's own memory (HysteresisMemoryOfTheChain) may
  // be named too: with the load on the distal load the rest of the gap is
  // the hysteresis the paper's single state lacks. Nothing else.
  ASSERT_GE(g.effects.size(), 1U);
  for (std::size_t k = 1; k < g.effects.size(); ++k)
    EXPECT_EQ(g.effects[k].name, "hysteresis_elements") << ::testing::PrintToString(names(g));
  if (g.effects.front().name != "load_dependent") {
    ASSERT_FALSE(g.confounds.empty()) << g.effects.front().name << " named confidently";
    EXPECT_EQ(g.confounds.front().rival, "load_dependent");
    EXPECT_FALSE(g.effects.front().confounded_with.empty());
  }
  // Named, and the gap shrinks by more than the margin; it does not reach
  // the floor (docs/model-gap.md: the plant's capstan friction follows the
  // sheath tensions, which |tau_in| / R only approximates).
  EXPECT_LE(g.gap_final.rmse, 0.85 * g.gap_base.rmse);
}

TEST(GapVirtualSlave, PalpationReportsTheLoadPositionConfound) {
  // Pressing the tissue: the load follows the angle, so load and position
  // dependence explain the same residual. Never one confident name: both are
  // reported, with the experiment that separates them.
  const fs::path out =
      fs::temp_directory_path() / ("tsmh_gap_vs_palpate_" + std::to_string(::getpid()) + ".csv");
  const std::string cmd = std::string(TSMH_VIRTUAL_SLAVE) +
                          " --offline --duration 40 --scenario palpate --seed 7 --output " +
                          out.string() + " >/dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const Recording rec = read_recording_csv(out);
  fs::remove(out);
  const auto g = level_gap(rec, "paper");
  record(g, g.noise);
  ASSERT_FALSE(g.effects.empty());
  ASSERT_FALSE(g.confounds.empty());
  const std::set<std::string> pair = {g.confounds.front().named, g.confounds.front().rival};
  EXPECT_EQ(pair, (std::set<std::string>{"load_dependent", "position_dependent"}));
  EXPECT_FALSE(g.effects.front().confounded_with.empty());
  EXPECT_NE(g.confounds.front().warning.find("several positions"), std::string::npos)
      << g.confounds.front().warning;
}

TEST(GapVirtualSlave, TwoHiddenEffectsAreBothNamed) {
  // From the paper's model: the two switched-on effects and the chain's own
  // memory, three names. (From paper_memory, load_dependent imitates the
  // viscous drag first: in free motion |tau_in| / R is the friction, which
  // grows with speed; docs/model-gap.md.)
  const auto g = level_gap(
      virtual_slave("two", "--effect capstan=0 --effect viscous=2 --effect position=0.3"), "paper");
  const double floor = floor_of(virtual_slave("two_ctl", "--effect capstan=0"));
  record(g, floor);
  // The chain's memory may come as hysteresis_elements, distributed_slip
  // (its segments slip one after the other: distributed slip is its
  // physics) or both; the two switched-on effects must be named.
  const auto n = names(g);
  const std::set<std::string> found(n.begin(), n.end());
  EXPECT_TRUE(found.count("viscous")) << ::testing::PrintToString(n);
  EXPECT_TRUE(found.count("position_dependent")) << ::testing::PrintToString(n);
  EXPECT_TRUE(found.count("hysteresis_elements") || found.count("distributed_slip"))
      << ::testing::PrintToString(n);
  for (const auto& e : n)
    EXPECT_TRUE((std::set<std::string>{"viscous", "position_dependent", "hysteresis_elements",
                                       "distributed_slip"})
                    .count(e))
        << e << " was not hidden";
  EXPECT_LE(g.gap_final.rmse, 0.8 * g.gap_base.rmse);
}

// --- the command line -----------------------------------------------------

int run_tsm(const std::string& args, std::string& output) {
  const fs::path log =
      fs::temp_directory_path() / ("tsmh_gap_cli_" + std::to_string(::getpid()) + ".log");
  const std::string cmd = std::string(TSMH_TSM_BIN) + " " + args + " >" + log.string() + " 2>&1";
  const int rc = std::system(cmd.c_str());
  std::ifstream in(log);
  std::stringstream ss;
  ss << in.rdbuf();
  output = ss.str();
  fs::remove(log);
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

TEST(GapCommand, WritesTheContractReportSummaryParamsAndPlots) {
  const fs::path dir = fs::temp_directory_path() / ("tsmh_gap_cli_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  TsmModelSpec s = paper_spec();
  s.add(TermKind::kPositionDependent).p = {0.3, 0.2};
  SyntheticConfig c;
  c.seed = 118;
  c.duration_s = 20.0;
  write_recording_csv(make_synthetic(TsmFrictionModel(s), c).recording, dir / "data.csv");
  std::string out;
  ASSERT_EQ(
      run_tsm("gap " + (dir / "data.csv").string() + " --output " + (dir / "g").string(), out), 0)
      << out;
  std::ifstream in(dir / "g" / "report.json");
  const auto r = nlohmann::json::parse(in);
  EXPECT_EQ(r["base"], "paper");
  for (const char* k : {"rmse", "p2p", "fit_percent"}) {
    EXPECT_TRUE(r["gap_base"][k].is_number()) << k;
    EXPECT_TRUE(r["gap_final"][k].is_number()) << k;
  }
  // Each regime as tsm fit reports it too: its scores, share and errors.
  ASSERT_FALSE(r["regimes_base"].empty());
  for (const char* k : {"name", "group", "where", "rmse", "p2p", "fit_percent", "bias", "samples",
                        "concentration", "mean_error", "magnitude_excess"}) {
    EXPECT_TRUE(r["regimes_base"][0].contains(k)) << k;
    EXPECT_TRUE(r["regimes_final"][0].contains(k)) << k;
  }
  ASSERT_TRUE(r["effects"].is_array());
  ASSERT_FALSE(r["effects"].empty());
  EXPECT_EQ(r["effects"][0]["name"], "position_dependent");
  EXPECT_TRUE(r["effects"][0]["where"].is_string());
  EXPECT_TRUE(r["effects"][0]["gap_after"]["rmse"].is_number());
  for (const auto& p : r["plots"])
    EXPECT_TRUE(fs::exists(dir / "g" / p.get<std::string>())) << p;
  // Four plots, and the shape of each effect found against its variable.
  // (A shape flat at zero is not drawn; plots_not_written says which and why.)
  EXPECT_EQ(r["plots"].size(), 4U + r["effects"].size() - r["plots_not_written"].size())
      << r["warnings"];
  EXPECT_TRUE(r["effects"][0]["shape"].is_array());
  EXPECT_EQ(r["effects"][0]["variable"], "x");
  // The final params file carries the effect and is what simulate/fit load.
  const auto model = load_model((dir / "g" / "params.yaml").string());
  const auto* tsm = dynamic_cast<const TsmFrictionModel*>(model.get());
  ASSERT_NE(tsm, nullptr);
  EXPECT_TRUE(tsm->spec().has(TermKind::kPositionDependent));
  std::ifstream sum(dir / "g" / "summary.txt");
  std::stringstream text;
  text << sum.rdbuf();
  EXPECT_NE(text.str().find("Effect 1: position_dependent"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("Where:"), std::string::npos);
  // Every parenthesis the summary opens it closes (the stop message did not).
  const std::string t = text.str();
  EXPECT_EQ(std::count(t.begin(), t.end(), '('), std::count(t.begin(), t.end(), ')')) << t;
  // The fitted values it prints are params.yaml's (the final model), to the
  // 4 digits it prints: "name = value;".
  const auto final_params = model->parameters();
  std::size_t compared = 0;
  for (const auto& p : final_params) {
    const auto at = t.find(" " + p.name + " = ");
    if (at == std::string::npos) continue;
    const double printed = std::stod(t.substr(at + p.name.size() + 4));
    EXPECT_NEAR(printed, p.value, 5e-4 * std::max(1.0, std::fabs(p.value))) << p.name << "\n" << t;
    ++compared;
  }
  EXPECT_GT(compared, 0U) << t;
  // What the gap left means at the tip, in N m.
  EXPECT_NE(t.find("For haptics, the gap after: at the tool's tip"), std::string::npos) << t;
  fs::remove_all(dir);
}

TEST(GapCommand, BadDataWritesNothing) {
  const fs::path dir =
      fs::temp_directory_path() / ("tsmh_gap_cli_bad_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    std::ofstream f(dir / "flat.csv");
    f << "# radius_m: 0.01\nt,x_in,tau_in,tau_out\n";
    for (int i = 0; i < 6000; ++i)
      f << i * 1e-3 << ",0.1,0.01,0.0\n";
  }
  std::string out;
  EXPECT_NE(
      run_tsm("gap " + (dir / "flat.csv").string() + " --output " + (dir / "g").string(), out), 0);
  EXPECT_NE(out.find("no motion"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(dir / "g"));
  std::size_t entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    (void)e;
    ++entries;
  }
  EXPECT_EQ(entries, 1U);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace tsmh::estimator
