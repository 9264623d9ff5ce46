// The paper's tracking result (Fig. 8/9) on this plant: peak-to-peak joint
// tracking error on sinusoidal references, without and with compensation.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "virtual_tissue_slave/offline.hpp"

namespace vts = tsmh::virtual_tissue_slave;

namespace {

struct Errors {
  std::array<double, vts::kJoints> p2p{};
  std::array<double, vts::kJoints> backlash_estimate{};
};

// Peak-to-peak of reference - joint angle (joint encoder), after 10 s of warm-up.
Errors tracking_errors(bool compensation, const std::string& tissue, vts::Reroute reroute = {}) {
  vts::SlaveParams p = vts::paper_slave();
  for (auto& c : p.controllers)
    c.compensation = compensation;
  vts::OfflineOptions o;
  o.scenario = vts::make_scenario("sine");
  o.duration_s = 30.0;
  o.tissue = vts::tissue_preset(tissue);
  o.tissue->surface_rad = 0.6;
  o.reroute = reroute;
  std::array<double, vts::kJoints> hi{-1e9, -1e9}, lo{1e9, 1e9};
  const double from = std::isnan(reroute.at_s) ? 10.0 : reroute.at_s + 10.0;
  vts::run_offline(p, o, [&](const vts::SlaveSample& s) {
    if (s.t < from) return;
    for (std::size_t j = 0; j < vts::kJoints; ++j) {
      const double e = s.reference[j] - s.measured[j].x_out;
      hi[j] = std::max(hi[j], e);
      lo[j] = std::min(lo[j], e);
    }
  });
  Errors r;
  for (std::size_t j = 0; j < vts::kJoints; ++j)
    r.p2p[j] = hi[j] - lo[j];
  return r;
}

}  // namespace

TEST(Tracking, CompensationCutsPeakToPeakErrorAtLeastThreeTimes) {
  // Free motion, 0.8 rad sines at 0.5 Hz (Joint1) and 0.4 Hz (Joint2).
  const Errors without = tracking_errors(false, "none");
  const Errors with = tracking_errors(true, "none");
  for (std::size_t j = 0; j < vts::kJoints; ++j) {
    std::printf(
        "joint%zu: peak-to-peak tracking error %.4f rad without, %.4f rad with "
        "compensation (%.1fx); paper %s\n",
        j + 1, without.p2p[j], with.p2p[j], without.p2p[j] / with.p2p[j],
        j == 0 ? "0.2669 -> 0.0874" : "0.2823 -> 0.0646");
    const std::string key = "joint" + std::to_string(j + 1);
    ::testing::Test::RecordProperty(key + "_p2p_without", std::to_string(without.p2p[j]));
    ::testing::Test::RecordProperty(key + "_p2p_with", std::to_string(with.p2p[j]));
    EXPECT_GT(without.p2p[j], 0.2) << "the uncompensated slave should show paper-scale backlash";
    EXPECT_GE(without.p2p[j], 3.0 * with.p2p[j]) << "joint" << j + 1;
  }
}

TEST(Tracking, CompensationAlsoWorksInLightContact) {
  const Errors without = tracking_errors(false, "soft");
  const Errors with = tracking_errors(true, "soft");
  for (std::size_t j = 0; j < vts::kJoints; ++j)
    EXPECT_GE(without.p2p[j], 3.0 * with.p2p[j]) << "joint" << j + 1;
}

TEST(Tracking, AdaptationCopesWithSheathReRouting) {
  // At 10 s every sheath's wrap grows by 60 %: more friction, wider dead zone.
  vts::Reroute rr;
  rr.at_s = 10.0;
  rr.sheath1_wrap_rad = 3.4 * 1.6;
  const Errors without = tracking_errors(false, "none", rr);
  const Errors with = tracking_errors(true, "none", rr);
  for (std::size_t j = 0; j < vts::kJoints; ++j) {
    EXPECT_GT(without.p2p[j], 0.3) << "re-routing should widen the dead zone";
    EXPECT_GE(without.p2p[j], 3.0 * with.p2p[j]) << "joint" << j + 1;
  }
}
