// The model-gap workflow (`tsm gap`) on paper-model data with hidden effects
// of shapes the additive catalog does not have: the whole friction scaled by
// the distal load, friction x (1 + k |tau_out| / R); a ripple of short period
// along the stroke; viscous drag and the scaled load at once. Each must be
// named right and the validation gap must end within 1.3x the sensor floor:
// the RMS of the measured friction (tau_in - tau_out) / R less the true
// friction, which the synthetic world knows.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include "estimator/model_gap.hpp"
#include "estimator/model_io.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"
#include "gap_record.hpp"

namespace tsmh::estimator {
namespace {

constexpr double kFloorRatio = 1.3;

struct Injected {
  TermKind kind;
  std::vector<double> p;
};

struct World {
  Recording rec;
  double floor = 0.0;  // N, RMS of measured less true friction
};

World paper_world(std::uint64_t seed, const std::vector<Injected>& hidden) {
  TsmModelSpec s = paper_spec();
  for (const auto& h : hidden) {
    Term& t = s.add(h.kind);
    for (std::size_t k = 0; k < h.p.size(); ++k)
      t.p[k] = h.p[k];
  }
  SyntheticConfig c;
  c.seed = seed;
  SyntheticData data = make_synthetic(TsmFrictionModel(s), c);
  World w{std::move(data.recording), 0.0};
  double sum = 0.0;
  for (std::size_t i = 0; i < w.rec.size(); ++i) {
    const double measured = (w.rec.tau_in[i] - w.rec.tau_out[i]) / w.rec.radius_m;
    sum += (measured - data.true_friction[i]) * (measured - data.true_friction[i]);
  }
  w.floor = std::sqrt(sum / static_cast<double>(w.rec.size()));
  return w;
}

GapResult gap(const Recording& rec) {
  return find_model_gaps(rec, *load_model("paper"), "paper");
}

std::set<std::string> names(const GapResult& g) {
  std::set<std::string> n;
  for (const auto& e : g.effects)
    n.insert(e.name);
  return n;
}

void record(const GapResult& g, double floor) {
  record_gap_against_floor(g, floor);
  std::string rounds;
  for (const auto& r : g.rounds) {
    rounds += "[";
    for (const auto& t : r.trials)
      rounds += t.name + " " + std::to_string(t.gain) + (t.qualifies ? "*" : "") + ", ";
    rounds += "] ";
  }
  ::testing::Test::RecordProperty("rounds", rounds);
}

void expect_within_floor(const GapResult& g, double floor) {
  EXPECT_LE(g.gap_final.rmse, kFloorRatio * floor)
      << "gap " << g.gap_base.rmse << " -> " << g.gap_final.rmse << " N, sensor floor " << floor
      << " N (ratio " << g.gap_final.rmse / floor << ")";
}

TEST(GapHiddenShapes, FrictionScaledByTheDistalLoad) {
  // friction x (1 + 0.08 |D|), D = tau_out / R up to 6 N: up to 1.5x the
  // friction in contact. |tau_in| / R (load_dependent's additive form)
  // contains the friction itself and cannot express it.
  const World w = paper_world(131, {{TermKind::kLoadScaling, {0.08, 0.0}}});
  const auto g = gap(w.rec);
  record(g, w.floor);
  ASSERT_EQ(names(g), std::set<std::string>{"load_dependent"});
  EXPECT_EQ(g.effects.front().form, "load_scaling");
  EXPECT_EQ(g.effects.front().variable, "distal_load");
  EXPECT_TRUE(g.effects.front().confounded_with.empty());
  expect_within_floor(g, w.floor);
}

TEST(GapHiddenShapes, ShortPeriodRipple) {
  // 20 periods over the stroke (about 2 rad): beyond the 12 periods the
  // ripple's scan used to stop at.
  const double k = 2.0 * std::numbers::pi * 20.0 / 2.0;
  const World w = paper_world(132, {{TermKind::kPositionRipple, {0.2, 0.1, k}}});
  const auto g = gap(w.rec);
  record(g, w.floor);
  ASSERT_EQ(names(g), std::set<std::string>{"position_dependent"});
  EXPECT_EQ(g.effects.front().form, "position_ripple");
  // Its line quotes the base's error in the position regimes, not the
  // direction regimes.
  EXPECT_NE(g.effects.front().where.find("low_position"), std::string::npos)
      << g.effects.front().where;
  EXPECT_EQ(g.effects.front().where.find("positive_velocity"), std::string::npos)
      << g.effects.front().where;
  expect_within_floor(g, w.floor);
}

TEST(GapHiddenShapes, ViscousDragPlusScaledLoad) {
  const World w =
      paper_world(133, {{TermKind::kViscous, {0.3}}, {TermKind::kLoadScaling, {0.08, 0.0}}});
  const auto g = gap(w.rec);
  record(g, w.floor);
  EXPECT_EQ(names(g), (std::set<std::string>{"viscous", "load_dependent"}));
  expect_within_floor(g, w.floor);
}

}  // namespace
}  // namespace tsmh::estimator
