// The hysteresis_elements term: eq. (4)'s state as two parallel elements.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "estimator/model_io.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

// Constant-speed strokes: to `a` and back by `back`, then forward again by
// `back`; the friction at each sample.
std::vector<double> strokes(TsmFrictionModel& model, double a, double back) {
  std::vector<double> f;
  const double dt = 1e-3, speed = 0.2;
  double x = 0.0, t = 0.0;
  const auto move = [&](double to) {
    const double dir = to > x ? 1.0 : -1.0;
    while (dir * (to - x) > 1e-12) {
      const double step = std::min(speed * dt, std::fabs(to - x));
      x += dir * step;
      t += dt;
      f.push_back(model.step(Motion{t, x, dir * speed, 0.0, 0.0, 10.0}, dt));
    }
  };
  move(a);
  move(a - back);
  move(a);
  return f;
}

TsmModelSpec base() {
  TsmModelSpec s = dahl_spec();  // one level, no offset: the state alone
  s.n = 2.0;
  return s;
}

TEST(HysteresisMemory, WithoutAShareItIsThePaperStateBitForBit) {
  TsmModelSpec with = paper_spec();
  with.add(TermKind::kHysteresisElements).p = {0.0, 10.0};
  TsmFrictionModel a(paper_spec()), b(with);
  const auto fa = strokes(a, 0.5, 0.02), fb = strokes(b, 0.5, 0.02);
  ASSERT_EQ(fa.size(), fb.size());
  for (std::size_t i = 0; i < fa.size(); ++i)
    ASSERT_EQ(fa[i], fb[i]) << "sample " << i;
}

TEST(HysteresisMemory, TwoEqualElementsAreOne) {
  TsmModelSpec with = paper_spec();
  with.add(TermKind::kHysteresisElements).p = {0.4, 1.0};
  TsmFrictionModel a(paper_spec()), b(with);
  const auto fa = strokes(a, 0.5, 0.02), fb = strokes(b, 0.5, 0.02);
  for (std::size_t i = 0; i < fa.size(); ++i)
    ASSERT_NEAR(fa[i], fb[i], 1e-12 * std::fabs(fa[i]) + 1e-12) << "sample " << i;
}

TEST(HysteresisMemory, ASmallReversalIsUndoneByAShortReturn) {
  // Saturate, reverse 0.02 rad, return 0.02 rad: with a stiff element the
  // friction comes back closer to its level before the reversal than the
  // single state, whose return is as slow as its first transition.
  TsmModelSpec memory = base();
  memory.add(TermKind::kHysteresisElements).p = {0.5, 20.0};
  TsmFrictionModel single(base()), two(memory);
  const auto fs = strokes(single, 0.5, 0.02), fm = strokes(two, 0.5, 0.02);
  const std::size_t before = static_cast<std::size_t>(0.5 / 0.2 / 1e-3) - 1;
  const double level = fs[before];
  ASSERT_NEAR(fm[before], level, 1e-6 * level);  // both saturated at the same level
  const double dip_single = level - *std::min_element(fs.begin() + before, fs.end());
  const double dip_two = level - *std::min_element(fm.begin() + before, fm.end());
  EXPECT_GT(dip_single, 0.1 * level);
  EXPECT_GT(dip_two, 0.1 * level);
  const double left_single = level - fs.back(), left_two = level - fm.back();
  EXPECT_LT(left_two, 0.6 * left_single) << "single " << left_single << ", two " << left_two;
}

TEST(HysteresisMemory, PresetStartsEveryElementAtTheFriction) {
  TsmFrictionModel model(paper_memory_spec());
  const Motion rest{0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
  model.preset(3.0, rest);
  EXPECT_NEAR(model.friction(), 3.0, 1e-12);
  // Standing still leaves it there: no element drifts towards another.
  EXPECT_NEAR(model.step(rest, 1e-3), 3.0, 1e-12);
}

TEST(HysteresisMemory, ThePresetReadsBackFromItsYaml) {
  const auto model = load_model("paper_memory");
  const auto again = parse_model(model_to_yaml(*model, {}), "round trip");
  const auto p = model->parameters(), q = again->parameters();
  ASSERT_EQ(p.size(), q.size());
  bool found = false;
  for (std::size_t i = 0; i < p.size(); ++i) {
    EXPECT_EQ(p[i].name, q[i].name);
    EXPECT_DOUBLE_EQ(p[i].value, q[i].value);
    found = found || p[i].name == "hysteresis_elements.r2";
  }
  EXPECT_TRUE(found);
}

}  // namespace
}  // namespace tsmh::estimator
