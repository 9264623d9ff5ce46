// What a model-gap test found, as test properties (in ctest's XML output):
// the gap before and after, the sensor floor, their ratio and the effects
// named with their forms. Shared by the tests that judge the gap against a
// sensor floor.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "estimator/model_gap.hpp"

namespace tsmh::estimator {

inline void record_gap_against_floor(const GapResult& g, double floor) {
  ::testing::Test::RecordProperty("gap_base_rmse", std::to_string(g.gap_base.rmse));
  ::testing::Test::RecordProperty("gap_final_rmse", std::to_string(g.gap_final.rmse));
  ::testing::Test::RecordProperty("sensor_floor", std::to_string(floor));
  ::testing::Test::RecordProperty("ratio", std::to_string(g.gap_final.rmse / floor));
  std::string found;
  for (const auto& e : g.effects)
    found += e.name + "(" + e.form + ") ";
  ::testing::Test::RecordProperty("effects", found);
}

}  // namespace tsmh::estimator
