// Drift alarm and one-button recalibration: the DriftMonitor and
// Recalibration on a joint swept in free space whose friction is the paper
// model's times a routing factor k, and the loop end to end in simulated
// time with an in-memory link.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <tuple>

#include "estimator/tsm_model.hpp"
#include "fakes.hpp"
#include "haptics/drift_monitor.hpp"
#include "haptics/haptic_loop.hpp"
#include "haptics/recalibration.hpp"

namespace tsmh::haptics {
namespace {

constexpr double kR = 0.01;

// A joint swept at `amp` rad, `hz`, exact motion; the model's friction F
// (the paper's preset) and a proximal torque k R F + load + noise, as the
// estimator would report it with scale 1.
class Sweep {
 public:
  Sweep(double k, double amp = 0.6, double hz = 0.5, std::uint64_t seed = 1)
      : k_(k), amp_(amp), w_(2.0 * std::numbers::pi * hz), rng_(seed) {}
  // The plant's friction from `plant` instead of the model's (a transition
  // the model does not match), times k.
  Sweep(double k, double amp, double hz, const estimator::TsmModelSpec& plant) : Sweep(k, amp, hz) {
    plant_.emplace(plant);
  }
  // `load`: a distal torque added to tau_in (contact), N m.
  estimator::Estimate next(double load = 0.0) {
    t_ += 1e-3;
    estimator::Motion m;
    m.t = t_;
    m.x = amp_ * std::sin(w_ * t_);
    m.xd = amp_ * w_ * std::cos(w_ * t_);
    m.xdd = -amp_ * w_ * w_ * std::sin(w_ * t_);
    m.acc_sign = estimator::sign_of(m.xdd);
    const double f = model_.step(m, 1e-3);
    const double f_plant = plant_ ? plant_->step(m, 1e-3) : f;
    estimator::Estimate e;
    e.valid = true;
    e.xd = m.xd;
    e.xdd = m.xdd;
    e.acc_sign = m.acc_sign;
    e.friction = f;
    e.friction_level = model_.sliding_friction();
    e.tau_in = k_ * kR * f_plant + load + noise_(rng_);
    e.tau_out_est = e.tau_in - kR * f;
    x_ = m.x;
    return e;
  }
  double t() const { return t_; }
  double x() const { return x_; }
  void set_k(double k) { k_ = k; }
  // What the loop does in RecalibrationScale::kLevels: the estimator's model
  // runs at the applied scale.
  void set_model_level_scales(double k_positive, double k_negative) {
    model_.set_level_scales(k_positive, k_negative);
  }
  // The plant's own levels, scaled per direction of sliding (a bend that
  // wraps the pair's two sheaths by different amounts).
  void set_plant_level_scales(double k_positive, double k_negative) {
    if (!plant_) plant_.emplace(estimator::paper_spec());
    plant_->set_level_scales(k_positive, k_negative);
  }

 private:
  double k_, amp_, w_;
  double t_ = 0.0, x_ = 0.0;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 0.003};
  estimator::TsmFrictionModel model_{estimator::paper_spec()};
  std::optional<estimator::TsmFrictionModel> plant_;
};

TEST(DriftMonitor, NoAlarmWhileTheModelFitsEvenWithOneSidedContact) {
  DriftMonitor d;
  Sweep s(1.0);
  for (int i = 0; i < 300'000; ++i) {  // 5 minutes
    // Tissue beyond 0.3 rad pushing back 0.4 N m/rad: a one-sided load.
    const double load = s.x() > 0.3 ? 0.4 * (s.x() - 0.3) : 0.0;
    d.update(s.t() + 1e-3, s.next(load), kR);
    ASSERT_FALSE(d.alarm()) << "t = " << s.t() << " scale " << d.scale();
  }
  EXPECT_TRUE(d.judged());
  EXPECT_NEAR(d.scale(), 1.0, 0.1);
}

TEST(DriftMonitor, AlarmsWithinSecondsOfARerouteAndClearsAfterTheFix) {
  DriftMonitor d;
  Sweep s(1.0);
  for (int i = 0; i < 20'000; ++i)
    d.update(s.t() + 1e-3, s.next(), kR);
  ASSERT_FALSE(d.alarm());
  s.set_k(1.5);  // the re-route: friction 1.5x
  double raised = -1.0;
  for (int i = 0; i < 10'000 && raised < 0.0; ++i) {
    d.update(s.t() + 1e-3, s.next(), kR);
    if (d.alarm()) raised = s.t() - 20.0;
  }
  ASSERT_GT(raised, 0.0) << "no alarm within 10 s";
  EXPECT_LT(raised, 5.0);
  EXPECT_NEAR(d.scale(), 1.5, 0.15);
  s.set_k(1.0);  // the model fits again (as after a recalibration)
  for (int i = 0; i < 15'000; ++i)
    d.update(s.t() + 1e-3, s.next(), kR);
  EXPECT_FALSE(d.alarm());
}

// A plant whose friction transition after a reversal is twice as long as
// the model's (theta halved): its levels match, so long strokes see no drift.
estimator::TsmModelSpec slow_transition_plant() {
  auto spec = estimator::paper_spec();
  spec.theta *= 0.5;
  return spec;
}

// The largest |scale - 1| while judged, and whether the alarm rose, over
// `seconds` of a sweep.
struct Judged {
  double max_off = 0.0;
  bool alarm = false;
  bool judged = false;
};
Judged run_monitor(DriftMonitor& d, Sweep& s, double seconds) {
  Judged j;
  for (int i = 0; i < static_cast<int>(seconds * 1000.0); ++i) {
    d.update(s.t() + 1e-3, s.next(), kR);
    if (d.judged()) j.max_off = std::max(j.max_off, std::fabs(d.scale() - 1.0));
    j.judged = j.judged || d.judged();
    j.alarm = j.alarm || d.alarm();
  }
  return j;
}

TEST(DriftMonitor, ASwayThatNeverLeavesTheTransitionRaisesNoAlarm) {
  // Strokes of 0.08 rad p-p at 1.2 Hz: sliding (|xd| up to 0.3 rad/s) but
  // the friction never reaches its level. Unsaturated samples would give
  // the transition's mismatch as a scale (the live false alarm: joint 1
  // swaying 0.05 rad raised the alarm once at scale 1.26).
  DriftConfig no_gate;
  no_gate.min_saturation = 0.0;
  DriftMonitor ungated(no_gate);
  Sweep s1(1.0, 0.04, 1.2, slow_transition_plant());
  const Judged before = run_monitor(ungated, s1, 60.0);
  ASSERT_TRUE(before.judged);
  EXPECT_GT(before.max_off, 0.25) << "the test's sway must mislead an ungated monitor";

  DriftMonitor gated;
  Sweep s2(1.0, 0.04, 1.2, slow_transition_plant());
  const Judged after = run_monitor(gated, s2, 60.0);
  EXPECT_FALSE(after.alarm);
  EXPECT_LT(after.max_off, 0.125) << "judged " << after.judged;
}

TEST(DriftMonitor, TheSaturationGateKeepsLongStrokesAndDrift) {
  // The same plant on 0.6 rad strokes: judged, no alarm on unchanged
  // routing (less scale error than without the gate), and a 1.5x re-route
  // still found.
  DriftConfig no_gate;
  no_gate.min_saturation = 0.0;
  DriftMonitor ungated(no_gate);
  Sweep s0(1.0, 0.6, 0.5, slow_transition_plant());
  const Judged reference = run_monitor(ungated, s0, 30.0);
  DriftMonitor d;
  Sweep s(1.0, 0.6, 0.5, slow_transition_plant());
  const Judged unchanged = run_monitor(d, s, 30.0);
  ASSERT_TRUE(unchanged.judged);
  EXPECT_FALSE(unchanged.alarm);
  // The transition's mismatch reads as scale on unsaturated samples even on
  // long strokes (0.25 ungated, at the threshold): the gate removes part of it.
  EXPECT_LT(unchanged.max_off, 0.2);
  EXPECT_LT(unchanged.max_off, reference.max_off - 0.05);
  s.set_k(1.5);
  const Judged rerouted = run_monitor(d, s, 5.0);
  EXPECT_TRUE(rerouted.alarm);
  EXPECT_NEAR(d.scale(), 1.5, 0.15);
}

// Drives a Recalibration like the loop does: on_tick each ms, on_estimate
// per sample; the identification runs synchronously where the server's main
// thread would run it. Without a replica of the model the scale goes to the
// model's output (kOutput); `CalibRig::levels` gives it one (kLevels).
struct CalibRig {
  explicit CalibRig(double k, double amp = 0.6)
      : sweep(k, amp), calib(1, RecalibrationConfig{}, DriftConfig{}) {}
  CalibRig(Sweep s, std::vector<std::unique_ptr<estimator::FrictionModel>> replicas)
      : CalibRig(std::move(s), std::move(replicas), RecalibrationConfig{}) {}
  CalibRig(Sweep s, std::vector<std::unique_ptr<estimator::FrictionModel>> replicas,
           const RecalibrationConfig& config)
      : sweep(std::move(s)), calib(1, config, DriftConfig{}, std::move(replicas)) {}
  static CalibRig levels(Sweep s, const RecalibrationConfig& config = {}) {
    std::vector<std::unique_ptr<estimator::FrictionModel>> r;
    r.push_back(std::make_unique<estimator::TsmFrictionModel>(estimator::paper_spec()));
    return CalibRig(std::move(s), std::move(r), config);
  }
  void run(double seconds, double load_per_rad_beyond = 0.0, bool button = false) {
    const int n = static_cast<int>(seconds * 1000.0);
    for (int i = 0; i < n; ++i) {
      calib.on_tick(sweep.t(), 1e-3, button && i < 100);
      if (calib.scales_levels(0))
        sweep.set_model_level_scales(calib.applied_scale(0, false), calib.applied_scale(0, true));
      const double x = sweep.x();
      auto e = sweep.next(x > 0.3 ? load_per_rad_beyond * (x - 0.3) : 0.0);
      const double raw_f = e.friction;
      calib.on_estimate(0, sweep.t(), sweep.x(), e, kR);
      // kOutput: the scale reaches the estimate exactly, F x applied scale;
      // kLevels: the model already ran at it, the estimate is left alone.
      const double expected = calib.scales_levels(0) ? raw_f : raw_f * calib.applied_scale(0);
      ASSERT_DOUBLE_EQ(e.friction, expected);
      applied.push_back(calib.applied_scale(0));
      friction.push_back(e.friction);
      calib.identify_pending();
    }
  }
  Sweep sweep;
  Recalibration calib;
  std::vector<double> applied, friction;
};

// The paper's model with every level term x k and theta kept: a sheath
// re-routed to k times the friction (the levels grow with the wrap, the
// tendon's stiffness does not).
estimator::TsmModelSpec rerouted_plant(double k) {
  auto spec = estimator::paper_spec();
  for (auto& t : spec.terms) {
    switch (t.kind) {
      case estimator::TermKind::kCoulomb:
      case estimator::TermKind::kDirectionAsymmetry:
      case estimator::TermKind::kStribeck:
        t.p[0] *= k;
        break;
      case estimator::TermKind::kAccelerationDependence:
        t.p[0] *= k;
        t.p[2] *= k;
        break;
      default:
        break;
    }
  }
  return spec;
}

TEST(Recalibration, ButtonThenFreeMotionFindsTheNewScaleAndRampsItIn) {
  CalibRig rig(1.5);
  rig.run(2.0);
  EXPECT_EQ(rig.calib.state(), CalibrationState::kIdle);
  rig.run(0.2, 0.0, true);  // the button
  EXPECT_EQ(rig.calib.state(), CalibrationState::kCollecting);
  rig.run(5.0);
  ASSERT_EQ(rig.calib.state(), CalibrationState::kApplied) << to_string(rig.calib.reason());
  EXPECT_NEAR(rig.calib.target_scale(0), 1.5, 0.05);
  const auto f = rig.calib.figures(0);
  EXPECT_LT(f.rms_new, 0.5 * f.rms_old);
  rig.run(2.0);
  EXPECT_NEAR(rig.calib.applied_scale(0), rig.calib.target_scale(0), 1e-12);
  // No jump: the scale moved at most ramp_per_s x 1 ms per tick.
  for (std::size_t i = 1; i < rig.applied.size(); ++i)
    ASSERT_LE(std::fabs(rig.applied[i] - rig.applied[i - 1]), 0.5e-3 + 1e-12) << i;
}

TEST(Recalibration, LevelsFindARerouteOfTheLevelsAndKeepTheTransition) {
  // A plant whose levels grew 1.5x with theta kept. Scaling the levels finds
  // it; scaling the output (levels and theta) can only approximate it.
  const auto run = [](CalibRig rig) {
    rig.run(1.0);
    rig.calib.request(1);
    rig.run(5.5);
    EXPECT_EQ(rig.calib.state(), CalibrationState::kApplied) << to_string(rig.calib.reason());
    return std::pair{rig.calib.target_scale(0), rig.calib.figures(0)};
  };
  const auto [k_levels, f_levels] =
      run(CalibRig::levels(Sweep(1.0, 0.6, 0.5, rerouted_plant(1.5))));
  const auto [k_output, f_output] = run(CalibRig(Sweep(1.0, 0.6, 0.5, rerouted_plant(1.5)), {}));
  EXPECT_NEAR(k_levels, 1.5, 0.02);
  // The replay at the scale found leaves about the sensor noise (3 mN m).
  EXPECT_LT(f_levels.rms_new, 0.0045);
  EXPECT_LT(f_levels.rms_new, 0.7 * f_output.rms_new)
      << "levels " << f_levels.rms_new << ", output " << f_output.rms_new << " (k " << k_output
      << ")";
}

TEST(Recalibration, EachDirectionGetsItsOwnLevelScale) {
  // A bend that grew the positive direction's friction 1.6x and the
  // negative one's 1.3x. Per direction (the default) finds both; one common
  // scale can only split the difference and fits the data worse.
  const auto run = [](bool per_direction) {
    Sweep plant(1.0, 0.6, 0.5);
    plant.set_plant_level_scales(1.6, 1.3);
    RecalibrationConfig config;
    config.per_direction = per_direction;
    CalibRig rig = CalibRig::levels(std::move(plant), config);
    rig.run(1.0);
    rig.calib.request(1);
    rig.run(8.0);  // collect 5 s, identify, ramp in
    EXPECT_EQ(rig.calib.state(), CalibrationState::kApplied) << to_string(rig.calib.reason());
    return std::tuple{rig.calib.figures(0), rig.calib.applied_scale(0, false),
                      rig.calib.applied_scale(0, true)};
  };
  const auto [both, applied_positive, applied_negative] = run(true);
  EXPECT_NEAR(both.scale_positive, 1.6, 0.03);
  EXPECT_NEAR(both.scale_negative, 1.3, 0.03);
  EXPECT_NEAR(applied_positive, both.scale_positive, 1e-12);
  EXPECT_NEAR(applied_negative, both.scale_negative, 1e-12);
  EXPECT_LT(both.rms_new, 0.0045);  // about the sensor noise (3 mN m)
  EXPECT_LT(both.rms_new, 0.8 * both.rms_common);
  const auto common = std::get<0>(run(false));
  EXPECT_DOUBLE_EQ(common.scale_positive, common.scale_negative);
  EXPECT_GT(common.scale, 1.3);
  EXPECT_LT(common.scale, 1.6);
  EXPECT_DOUBLE_EQ(common.rms_new, common.rms_common);
  EXPECT_LT(both.rms_new, 0.8 * common.rms_new);
}

TEST(Recalibration, LevelsComeInWithoutAJumpInFriction) {
  CalibRig rig = CalibRig::levels(Sweep(1.0, 0.6, 0.5, rerouted_plant(1.5)));
  ASSERT_TRUE(rig.calib.scales_levels(0));
  rig.run(1.0);
  rig.calib.request(1);
  rig.run(9.0);  // collect, identify, ramp in (1 -> 1.5 at 0.5/s: 1 s)
  ASSERT_NEAR(rig.calib.applied_scale(0), 1.5, 0.02);
  // A change of the level moves the state's target, not the state: the
  // friction stays as smooth as the motion makes it.
  double worst = 0.0, worst_before = 0.0;
  for (std::size_t i = 1; i < rig.friction.size(); ++i) {
    const double d = std::fabs(rig.friction[i] - rig.friction[i - 1]);
    (i < 1000 ? worst_before : worst) = std::max(i < 1000 ? worst_before : worst, d);
  }
  EXPECT_LE(worst, 1.6 * worst_before);
}

TEST(Recalibration, ModelsWithoutALevelScaleTheOutput) {
  std::vector<std::unique_ptr<estimator::FrictionModel>> none;
  none.push_back(nullptr);
  Recalibration a(1, RecalibrationConfig{}, DriftConfig{}, std::move(none));
  EXPECT_FALSE(a.scales_levels(0));
  RecalibrationConfig output;
  output.scale = RecalibrationScale::kOutput;
  std::vector<std::unique_ptr<estimator::FrictionModel>> tsm;
  tsm.push_back(std::make_unique<estimator::TsmFrictionModel>(estimator::paper_spec()));
  Recalibration b(1, output, DriftConfig{}, std::move(tsm));
  EXPECT_FALSE(b.scales_levels(0));
}

TEST(Recalibration, RefusesWithTheReason) {
  {  // unchanged routing: the new scale is no better
    CalibRig rig(1.0);
    rig.calib.request(1);
    rig.run(6.0);
    EXPECT_EQ(rig.calib.state(), CalibrationState::kRefused);
    EXPECT_EQ(rig.calib.reason(), CalibrationReason::kNotBetter);
    EXPECT_EQ(rig.calib.reason_joint(), 0);
    EXPECT_DOUBLE_EQ(rig.calib.applied_scale(0), 1.0);
  }
  {  // a tiny stroke
    CalibRig rig(1.5, 0.05);
    rig.calib.request(1);
    rig.run(6.0);
    EXPECT_EQ(rig.calib.reason(), CalibrationReason::kMotionTooSmall);
    EXPECT_DOUBLE_EQ(rig.calib.applied_scale(0), 1.0);
  }
  {  // pressing tissue while "calibrating"
    CalibRig rig(1.5);
    rig.calib.request(1);
    rig.run(6.0, 0.8);
    EXPECT_EQ(rig.calib.reason(), CalibrationReason::kNotFree);
    EXPECT_DOUBLE_EQ(rig.calib.applied_scale(0), 1.0);
  }
}

// The loop end to end: an LCM-style request through the link, collection in
// the loop, identification outside it, the new scale in HAPTIC_STATUS, and
// the drift flag before it.
TEST(Recalibration, LoopTakesARequestFromTheLinkAndReportsInStatus) {
  testing::FakeDevice device;
  testing::FakeLink link;
  LoopConfig c;
  c.joints = 2;
  for (int j = 0; j < 2; ++j) {
    c.force[j] = {1.0, 1.0, 0.0};
    c.limits[j] = {0.8, 100.0};
  }
  std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> est;
  for (int j = 0; j < 2; ++j)
    est.push_back(std::make_unique<estimator::DistalTorqueEstimator>(
        std::make_unique<estimator::TsmFrictionModel>(estimator::paper_spec()), kR,
        estimator::DifferentiatorConfig{}, estimator::StartState::kZero));
  HapticLoop loop(c, device, link, std::move(est));
  // The "slave": friction of the same model at 1.5x, on the measured motion.
  estimator::DistalTorqueEstimator twin(
      std::make_unique<estimator::TsmFrictionModel>(estimator::paper_spec()), kR,
      estimator::DifferentiatorConfig{}, estimator::StartState::kZero);
  std::int64_t now = 1'000'000'000;
  double last_torque = 0.0, worst_step = 0.0;
  bool drift_seen = false;
  const auto run = [&](double seconds) {
    for (int i = 0; i < static_cast<int>(seconds * 1000); ++i, now += 1'000'000) {
      const double t = static_cast<double>(now) * 1e-9;
      const double x = 0.6 * std::sin(std::numbers::pi * t);
      const double f = twin.update(t, x, 0.0).friction;  // the model's F on this motion
      const double tau_in = 1.5 * kR * f;
      link.push(now, x, tau_in / kR, 0.0);
      loop.tick(now);
      worst_step = std::max(worst_step, std::fabs(device.torque[0] - last_torque));
      last_torque = device.torque[0];
      if (!link.statuses.empty() && (link.statuses.back().flags & status_flags::kDriftSuspected))
        drift_seen = true;
    }
  };
  run(10.0);
  EXPECT_TRUE(drift_seen);
  link.calibration_request.num_joints = 2;
  link.calibration_request.recalibrate = {true, true};
  link.calibration_version = 1;
  run(0.5);
  ASSERT_FALSE(link.statuses.empty());
  EXPECT_EQ(link.statuses.back().calibration_state,
            static_cast<std::int32_t>(CalibrationState::kCollecting));
  EXPECT_TRUE(link.statuses.back().flags & status_flags::kRecalibrating);
  run(5.0);
  EXPECT_TRUE(loop.calibration().identify_pending());  // the server's main thread
  const double before_swap = worst_step;
  run(3.0);
  const auto& st = link.statuses.back();
  EXPECT_EQ(st.calibration_state, static_cast<std::int32_t>(CalibrationState::kApplied));
  EXPECT_NEAR(st.friction_scale[0], 1.5, 0.1);
  EXPECT_NEAR(st.friction_scale[1], 1.5, 0.1);
  // The swap added no step beyond what the motion itself made.
  EXPECT_LE(worst_step, std::max(before_swap, 1e-3) * 1.05);
  run(10.0);
  EXPECT_FALSE(link.statuses.back().flags & status_flags::kDriftSuspected);
}

}  // namespace
}  // namespace tsmh::haptics
