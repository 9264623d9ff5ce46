// Server configuration: defaults, and every bad field named in the error.
#include <gtest/gtest.h>

#include "haptics/evaluation.hpp"
#include "haptics/server_config.hpp"

namespace tsmh::haptics {
namespace {

const std::string kJoint = "joints:\n  - {name: a, max_torque_nm: 0.3}\n";

std::string error_of(const std::string& yaml) {
  try {
    parse_server_config(yaml, "server.yaml", "/cfg");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(ServerConfig, DefaultsAreSafe) {
  const auto c = parse_server_config(kJoint, "server.yaml", "/cfg");
  EXPECT_EQ(c.loop.joints, 1);
  EXPECT_DOUBLE_EQ(c.loop.rate_hz, 1000.0);
  EXPECT_EQ(c.loop.status_every, 10);
  EXPECT_EQ(c.loop.source, FeedbackSource::kEstimated);
  EXPECT_DOUBLE_EQ(c.loop.timing.stale_after_s, 0.020);
  EXPECT_DOUBLE_EQ(c.loop.limits[0].max_torque_nm, 0.3);
  EXPECT_EQ(c.device_driver, "sim");
  EXPECT_EQ(c.joints[0].params, "paper");
  EXPECT_FALSE(c.evaluation.truth);
}

TEST(ServerConfig, RelativePathsResolveAgainstTheConfigFolder) {
  const auto c = parse_server_config(
      "joints:\n  - {params: fits/j0.yaml, max_torque_nm: 0.3}\nevaluation: {trace: out/t.csv}\n",
      "server.yaml", "/cfg");
  EXPECT_EQ(c.joints[0].params, "/cfg/fits/j0.yaml");
  EXPECT_EQ(c.evaluation.trace, "/cfg/out/t.csv");
}

TEST(ServerConfig, BadFieldsAreNamed) {
  EXPECT_NE(error_of("joints:\n  - {name: a}\n").find("joints[0].max_torque_nm: missing"),
            std::string::npos);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: -1}\n").find("joints[0].max_torque_nm"),
            std::string::npos);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: .nan}\n").find("joints[0].max_torque_nm"),
            std::string::npos);
  EXPECT_NE(
      error_of("joints:\n  - {max_torque_nm: 1, force_sign: 2}\n").find("joints[0].force_sign:"),
      std::string::npos);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: 1, force_sign: 0.5}\n")
                .find("joints[0].force_sign: must be 1 or -1"),
            std::string::npos);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: 1, torque_max: 2}\n")
                .find("joints[0].torque_max: unknown key"),
            std::string::npos);
  EXPECT_NE(error_of("rate_hz: 9000\n" + kJoint).find("rate_hz"), std::string::npos);
  EXPECT_NE(error_of("feedback: loud\n" + kJoint).find("feedback: 'loud'"), std::string::npos);
  EXPECT_NE(error_of("safety: {stale_after_ms: 0}\n" + kJoint).find("safety.stale_after_ms"),
            std::string::npos);
  EXPECT_NE(error_of("lcm: {url: [1, 2]}\n" + kJoint).find("lcm.url: must be a string"),
            std::string::npos);
  EXPECT_NE(error_of("realtime: {sched_fifo: maybe}\n" + kJoint).find("realtime.sched_fifo"),
            std::string::npos);
  EXPECT_NE(error_of("joints: []\n").find("joints: missing"), std::string::npos);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: 1, slave_min_rad: 1, slave_max_rad: 0}\n")
                .find("joints[0].slave_min_rad"),
            std::string::npos);
  EXPECT_NE(error_of("rate_hz: [\n").find("not valid YAML"), std::string::npos);
  EXPECT_NE(error_of("colour: blue\n" + kJoint).find("colour: unknown key"), std::string::npos);
}

TEST(ServerConfig, EstimatorSignAndStartStatePerJoint) {
  const auto c = parse_server_config(
      "joints:\n  - {max_torque_nm: 0.3}\n  - {max_torque_nm: 0.3, sign: hard, start_state: "
      "zero}\n",
      "server.yaml", "/cfg");
  EXPECT_EQ(c.joints[0].sign, estimator::SignMode::smooth);
  EXPECT_EQ(c.joints[0].start_state, estimator::StartState::free_tip);
  EXPECT_EQ(c.joints[1].sign, estimator::SignMode::hard);
  EXPECT_EQ(c.joints[1].start_state, estimator::StartState::zero);
  EXPECT_NE(error_of("joints:\n  - {max_torque_nm: 0.3, sign: soft}\n").find("joints[0].sign"),
            std::string::npos);
  EXPECT_NE(
      error_of("joints:\n  - {max_torque_nm: 0.3, start_state: x}\n").find("joints[0].start_state"),
      std::string::npos);
}

TEST(Evaluation, SlopeOfALine) {
  EXPECT_NEAR(slope({0, 1, 2, 3}, {1, 3, 5, 7}), 2.0, 1e-12);
  EXPECT_TRUE(std::isnan(slope({1, 1, 1}, {1, 2, 3})));
  EXPECT_TRUE(std::isnan(slope({1}, {1})));
}

}  // namespace
}  // namespace tsmh::haptics

namespace tsmh::haptics {
namespace {

// A press sweeping a soft layer (222 N/m, 4.5 mm) over a hard inclusion
// (1666 N/m) through a 30 mm lever: 0.2 and 1.5 N m/rad in joint space. The
// rendering is made 1.2x too stiff on purpose; the evaluation must see both.
TEST(Evaluation, FindsTheNoduleEdgeAndBothStiffnesses) {
  ServerConfig config =
      parse_server_config("joints:\n  - {force_scale: 0.6, max_torque_nm: 1}\n", "s.yaml", "/");
  Trace trace(1, 4000);
  for (int i = 0; i < 4000; ++i) {
    const double theta = 0.2 + 0.25 * (i % 2000) / 2000.0;  // two sweeps through the tissue
    const double ind = (theta - 0.2) * 0.03;
    const double force = 222.0 * std::min(ind, 0.0045) + 1666.0 * std::max(ind - 0.0045, 0.0);
    TraceRow row;
    row.state = static_cast<std::int32_t>(LoopState::kEnabled);
    auto& q = row.joints[0];
    q.true_tau_out = force * 0.03;
    q.true_x_out = theta;
    q.master_q = theta;
    q.torque_cmd = 0.6 * 1.2 * q.true_tau_out;
    q.indentation = ind;
    q.contact_force = force;
    trace.append(row);
  }
  const Discrimination d = discriminate(trace, config, 0);
  EXPECT_NEAR(d.boundary_m, 0.0045, 4e-4);
  EXPECT_NEAR(d.soft.truth, 222.0 * 0.03 * 0.03, 0.02);
  EXPECT_NEAR(d.hard.truth, 1666.0 * 0.03 * 0.03, 0.05);
  EXPECT_NEAR(d.soft.perceived, 1.2 * d.soft.truth, 0.02);
  EXPECT_NEAR(d.hard.perceived, 1.2 * d.hard.truth, 0.06);
  EXPECT_GT(d.soft.samples, 1000u);
  EXPECT_GT(d.hard.samples, 1000u);
  // The master follows the true joint angle here: a perfect estimate would
  // have felt the truth.
  EXPECT_NEAR(d.soft.ideal, d.soft.truth, 1e-9);
  EXPECT_NEAR(d.hard.ideal, d.hard.truth, 1e-9);
}

TEST(Evaluation, PhantomTorqueInFreeMotion) {
  // Half the ticks in free motion (true torque 0) rendering 0.01 N m where
  // naive feedback would render 0.6 x 0.05; half in contact.
  ServerConfig config =
      parse_server_config("joints:\n  - {force_scale: 0.6, max_torque_nm: 1}\n", "s.yaml", "/");
  Trace trace(1, 1000);
  for (int i = 0; i < 1000; ++i) {
    TraceRow row;
    row.state = static_cast<std::int32_t>(LoopState::kEnabled);
    auto& q = row.joints[0];
    const bool free = i % 2 == 0;
    q.true_tau_out = free ? 0.0 : 0.2;
    q.tau_in = free ? 0.05 : 0.25;
    q.tau_out_est = free ? 0.01 / 0.6 : 0.2;
    q.torque_cmd = 0.6 * q.tau_out_est;
    trace.append(row);
  }
  const JointEvaluation e = evaluate_joint(trace, config, 0);
  EXPECT_EQ(e.free_samples, 500u);
  EXPECT_NEAR(e.phantom_rendered, 0.01, 1e-12);
  EXPECT_NEAR(e.phantom_naive, 0.03, 1e-12);
  EXPECT_NEAR(e.phantom_ratio, 1.0 / 3.0, 1e-9);
  EXPECT_NEAR(e.rmse_naive, 0.05, 1e-12);
}

}  // namespace
}  // namespace tsmh::haptics
