// Distributed slip: the element family, its tension and load copies, the
// params file, the estimator's tension input and the exact solve of the
// linear block.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "estimator/distal_estimator.hpp"
#include "estimator/model_io.hpp"
#include "estimator/separable_fit.hpp"
#include "estimator/simulate.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

// A slip-only model: elements with the given widths and break forces, no
// sliding functions.
TsmModelSpec elements_only(int n, double wmin, double wmax, const std::vector<double>& w) {
  TsmModelSpec s;
  s.slip.enabled = true;
  s.slip.elements = n;
  s.slip.width_min = wmin;
  s.slip.width_max = wmax;
  for (int i = 0; i < n; ++i)
    s.slip.weight[static_cast<std::size_t>(i)] = w[static_cast<std::size_t>(i)];
  return s;
}

// An input with reversals of many sizes (nested minor loops).
std::vector<double> wandering_angle(std::size_t n, double dt) {
  std::vector<double> x(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * dt;
    x[i] = 0.4 * std::sin(1.1 * t) + 0.05 * std::sin(7.3 * t + 0.4) + 0.004 * std::sin(31.0 * t);
  }
  return x;
}

TEST(DistributedSlip, ElementFamilyIsAPrandtlIshlinskiiOperator) {
  // Prandtl-Ishlinskii: F = sum_i k_i (x - y_i), y_i the play operator of
  // half-width r_i: y_i = max(x - r_i, min(x + r_i, y_i)), starting at x(0).
  const int n = 7;
  const std::vector<double> w = {0.3, 0.9, 0.2, 1.4, 0.6, 0.05, 1.1};
  TsmFrictionModel model(elements_only(n, 2e-3, 0.25, w));
  const TsmModelSpec spec = model.spec();
  const double dt = 1e-3;
  const auto x = wandering_angle(20000, dt);
  std::vector<double> y(static_cast<std::size_t>(n), x[0]);
  model.reset();
  double worst = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    Motion m;
    m.t = static_cast<double>(k) * dt;
    m.x = x[k];
    const double f = model.step(m, dt);
    double ref = 0.0;
    for (int i = 0; i < n; ++i) {
      const auto u = static_cast<std::size_t>(i);
      const double r = spec.slip.width(u);
      y[u] = std::max(x[k] - r, std::min(x[k] + r, y[u]));
      ref += w[u] / r * (x[k] - y[u]);
    }
    worst = std::max(worst, std::fabs(f - ref));
  }
  EXPECT_LT(worst, 1e-9);
  // Log-uniform widths.
  EXPECT_NEAR(spec.slip.width(0), 2e-3, 1e-15);
  EXPECT_NEAR(spec.slip.width(6), 0.25, 1e-12);
  EXPECT_NEAR(spec.slip.width(3), std::sqrt(2e-3 * 0.25), 1e-12);
}

TEST(DistributedSlip, SaveRestoreAndLevelScalesKeepTheFriction) {
  TsmFrictionModel model(distributed_spec());
  EXPECT_FALSE(model.reads_acceleration_sign());
  const auto x = wandering_angle(3000, 1e-3);
  Motion m;
  for (std::size_t k = 0; k < 1500; ++k) {
    m.t = static_cast<double>(k) * 1e-3, m.x = x[k], m.xd = (x[k + 1] - x[k]) / 1e-3;
    model.step(m, 1e-3);
  }
  DynamicsState saved;
  ASSERT_TRUE(model.save_state(saved));
  std::vector<double> first, second;
  for (std::size_t k = 1500; k < 1600; ++k) {
    m.t = static_cast<double>(k) * 1e-3, m.x = x[k], m.xd = (x[k + 1] - x[k]) / 1e-3;
    first.push_back(model.step(m, 1e-3));
  }
  model.restore_state(saved);
  for (std::size_t k = 1500; k < 1600; ++k) {
    m.t = static_cast<double>(k) * 1e-3, m.x = x[k], m.xd = (x[k + 1] - x[k]) / 1e-3;
    second.push_back(model.step(m, 1e-3));
  }
  EXPECT_EQ(first, second);
  // A level scale leaves the friction of the instant (the elements' state
  // stays; at rest the sliding functions add nothing), and scales the level.
  TsmFrictionModel unscaled = model;
  ASSERT_TRUE(model.set_level_scales(1.5, 1.5));
  m.t += 1e-3;  // same angle, at rest
  m.xd = 0.0;
  EXPECT_EQ(model.step(m, 1e-3), unscaled.step(m, 1e-3));
  for (int k = 0; k < 3000; ++k) {
    m.t += 1e-3, m.x += 2e-3, m.xd = 2.0;
    model.step(m, 1e-3);
    unscaled.step(m, 1e-3);
  }
  // Catalog start: 7 N of elements + 3 N Coulomb (the Stribeck rise has
  // decayed at 2 rad/s).
  EXPECT_NEAR(unscaled.sliding_friction(), 10.0, 0.01);
  EXPECT_NEAR(model.sliding_friction(), 15.0, 0.015);
  EXPECT_NEAR(model.friction(), 15.0, 0.015);
}

TEST(DistributedSlip, LoadCopiesSolveTheDistalLoadExactly) {
  // F = A + B |u - F| with u = F + D: the model must return F for any D.
  TsmModelSpec s = distributed_spec();
  s.slip.load_copies = true;
  for (std::size_t i = 0; i < 14; ++i)
    s.slip.load_weight[i] = 0.02;
  s.slip.load_weight[kSlidingIndex] = 0.05;
  s.slip.load_weight[kSlidingIndex + 1] = 0.03;
  TsmFrictionModel with_load(s);
  TsmModelSpec plain_spec = s;
  plain_spec.slip.load_copies = false;
  TsmFrictionModel plain(plain_spec);
  const auto x = wandering_angle(4000, 1e-3);
  double worst = 0.0, largest_effect = 0.0;
  for (std::size_t k = 0; k + 1 < x.size(); ++k) {
    Motion m;
    m.t = static_cast<double>(k) * 1e-3, m.x = x[k], m.xd = (x[k + 1] - x[k]) / 1e-3;
    const double a = plain.step(m, 1e-3);
    // The basis is the same: B from the load weights.
    const SlipBasis& b = plain.slip_basis();
    double slope = 0.0;
    for (std::size_t i = 0; i < kMaxSlipBasis; ++i)
      slope += b.phi[i] * s.slip.load_weight[i];
    const double distal = 30.0 * std::sin(0.9 * m.t);  // N, tau_out / R
    const double f = a + slope * std::fabs(distal);
    m.drive = f + distal;
    const double got = with_load.step(m, 1e-3);
    worst = std::max(worst, std::fabs(got - f));
    largest_effect = std::max(largest_effect, std::fabs(f - a));
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(largest_effect, 1.0);  // the copies mattered
}

TEST(DistributedSlip, EstimatorCarriesTheTensionsAndSkipsTheSignCorrections) {
  TsmModelSpec s = distributed_spec();
  s.slip.tension_copies = true;
  s.slip.tension_ref = 20.0;
  for (std::size_t i = 0; i < 14; ++i)
    s.slip.tension_weight[i] = 0.05;  // each element 5 % of 1 N more per N of tension
  DistalTorqueEstimator est(std::make_unique<TsmFrictionModel>(s), 0.01);
  EXPECT_FALSE(est.hindsight());  // nothing reads sgn(xdd)
  DistalTorqueEstimator est2(std::make_unique<TsmFrictionModel>(s), 0.01);
  // The same drive torque R (T1 - T3), different pretension: the estimate
  // must differ by the tension copies' share (elements saturated).
  Estimate low, high;
  for (int k = 0; k < 2000; ++k) {
    const double t = k * 1e-3, x = 0.5 * t;         // slides at 0.5 rad/s
    low = est.update_tensions(t, x, 25.0, 15.0);    // mean 20 N
    high = est2.update_tensions(t, x, 35.0, 25.0);  // mean 30 N
  }
  ASSERT_TRUE(low.valid && high.valid);
  EXPECT_NEAR(low.tension, 20.0, 1e-12);
  EXPECT_NEAR(high.friction - low.friction, 7.0, 1e-6)
      << "10 N more mean tension x 0.05 per element x 14 saturated elements";
}

TEST(DistributedSlip, ParamsFileRoundTripsAndNamesBadFields) {
  TsmModelSpec s = distributed_spec();
  s.slip.tension_copies = true;
  s.slip.tension_ref = 21.5;
  s.slip.tension_weight[3] = 0.01;
  s.slip.load_copies = true;
  s.slip.load_weight[kSlidingIndex + 2] = -0.2;
  TsmFrictionModel model(s);
  const std::string yaml = model_to_yaml(model);
  const auto back = parse_model(yaml, "round.yaml");
  ASSERT_EQ(back->parameters().size(), model.parameters().size());
  for (std::size_t i = 0; i < model.parameters().size(); ++i) {
    EXPECT_EQ(back->parameters()[i].name, model.parameters()[i].name);
    EXPECT_NEAR(back->parameters()[i].value, model.parameters()[i].value,
                1e-9 * (1.0 + std::fabs(model.parameters()[i].value)));  // 10 digits in the file
  }
  const auto expect_error = [&](const std::string& from, const std::string& to,
                                const std::string& field) {
    std::string bad = yaml;
    const auto at = bad.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    bad.replace(at, from.size(), to);
    try {
      parse_model(bad, "bad.yaml");
      ADD_FAILURE() << "accepted " << to;
    } catch (const ParamsError& e) {
      EXPECT_NE(std::string(e.what()).find("bad.yaml"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  expect_error("width_max: 0.3", "width_max: 0.0001", "distributed_slip.width_max");
  expect_error("elements: 14", "elements: 30", "distributed_slip.elements");
  expect_error("elements: 14", "elements: 2.5", "distributed_slip.elements");
  expect_error("smoothing: 0.01", "smoothing: -1", "distributed_slip.smoothing");
  expect_error("load_weights: [0", "load_weights: [1.5", "distributed_slip.load_weights.e1");
  expect_error("weights: [0.5", "weights: [-0.5", "distributed_slip.weights.e1");
  expect_error("weights: [0.5", "weights: [0.1, 0.5", "distributed_slip.weights");
}

TEST(DistributedSlip, NonnegativeLeastSquaresMatchesEnumeration) {
  // 4 variables, the first three >= 0: compare with the best of all active sets.
  std::mt19937 rng(5);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::MatrixXd a(30, 4);
    Eigen::VectorXd y(30);
    for (int i = 0; i < 30; ++i) {
      for (int j = 0; j < 4; ++j)
        a(i, j) = g(rng);
      y(i) = g(rng);
    }
    const Eigen::MatrixXd gram = a.transpose() * a;
    const Eigen::VectorXd h = a.transpose() * y;
    const std::vector<bool> nonneg = {true, true, true, false};
    const auto x = nonnegative_least_squares({gram.data(), gram.data() + 16},
                                             {h.data(), h.data() + 4}, nonneg);
    const auto cost = [&](const Eigen::VectorXd& v) { return (a * v - y).squaredNorm(); };
    double best = std::numeric_limits<double>::infinity();
    for (int mask = 0; mask < 8; ++mask) {  // which constrained ones are free
      std::vector<int> idx = {3};
      for (int j = 0; j < 3; ++j)
        if (mask & (1 << j)) idx.push_back(j);
      Eigen::MatrixXd sub(30, static_cast<Eigen::Index>(idx.size()));
      for (std::size_t c = 0; c < idx.size(); ++c)
        sub.col(static_cast<Eigen::Index>(c)) = a.col(idx[c]);
      const Eigen::VectorXd s = sub.colPivHouseholderQr().solve(y);
      Eigen::VectorXd v = Eigen::VectorXd::Zero(4);
      bool feasible = true;
      for (std::size_t c = 0; c < idx.size(); ++c) {
        v(idx[c]) = s(static_cast<Eigen::Index>(c));
        if (idx[c] < 3 && v(idx[c]) < 0.0) feasible = false;
      }
      if (feasible) best = std::min(best, cost(v));
    }
    Eigen::VectorXd xv(4);
    for (int j = 0; j < 4; ++j)
      xv(j) = x[static_cast<std::size_t>(j)];
    for (int j = 0; j < 3; ++j)
      EXPECT_GE(xv(j), 0.0);
    EXPECT_NEAR(cost(xv), best, 1e-9 * (1.0 + best)) << "trial " << trial;
  }
}

// Synthetic data from a known distributed-slip model with tension and load
// copies: motion, mean tension and distal load varying independently.
// The first 0.5 s settles; then 2 s blocks alternate between training and
// validation, so both see every part of the motion.
SampleRole role_at(double t) {
  if (t < 0.5) return SampleRole::kIgnored;
  return static_cast<int>((t - 0.5) / 2.0) % 2 == 0 ? SampleRole::kTrain : SampleRole::kValidation;
}

FitData synthetic(const TsmModelSpec& truth, double noise, std::uint32_t seed) {
  FitData d;
  const double dt = 1e-3;
  const std::size_t n = 40000;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, noise);
  TsmModelSpec plain = truth;
  plain.slip.load_copies = false;
  plain.slip.drive_copies = false;
  TsmFrictionModel model(plain);
  model.reset();
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * dt;
    Motion m;
    m.t = t;
    m.x = 0.5 * std::sin(0.7 * t) + 0.15 * std::sin(2.9 * t + 1.0) + 0.02 * std::sin(11.0 * t);
    m.xd = 0.35 * std::cos(0.7 * t) + 0.435 * std::cos(2.9 * t + 1.0) + 0.22 * std::cos(11.0 * t);
    m.tension = 20.0 + 6.0 * std::sin(0.13 * t + 0.5);
    const double distal = 25.0 * std::sin(0.21 * t) * std::sin(0.05 * t + 0.3);
    const double a = model.step(m, dt);
    double slope = 0.0, drive_slope = 0.0;
    for (std::size_t i = 0; i < kMaxSlipBasis; ++i) {
      slope += model.slip_basis().phi[i] * truth.slip.load_weight[i];
      drive_slope += model.slip_basis().phi[i] * truth.slip.drive_weight[i];
    }
    // F = a + B |D| + C u with u = F + D (a truth has load or drive copies).
    const double f = (a + slope * std::fabs(distal) + drive_slope * distal) / (1.0 - drive_slope);
    m.drive = f + distal;
    d.motion.push_back(m);
    d.measured.push_back(f + g(rng));
    d.role.push_back(role_at(t));
  }
  d.radius_m = 0.01;
  return d;
}

TsmModelSpec known_truth() {
  TsmModelSpec s;
  s.slip.enabled = true;
  s.slip.elements = 10;
  s.slip.width_min = 2e-3;
  s.slip.width_max = 0.15;
  s.slip.smoothing = 0.02;
  s.slip.stribeck_speed = 0.15;
  s.slip.tension_copies = true;
  s.slip.tension_ref = 20.0;
  s.slip.load_copies = true;
  const double w[10] = {0.2, 0.5, 0.9, 0.0, 1.2, 0.7, 0.4, 0.0, 0.8, 0.3};
  for (std::size_t i = 0; i < 10; ++i) {
    s.slip.weight[i] = w[i];
    s.slip.tension_weight[i] = 0.03 * w[i];  // friction grows 3 % per N of tension
    s.slip.load_weight[i] = 0.01 * w[i];
  }
  s.slip.weight[kSlidingIndex + 0] = 3.0;
  s.slip.weight[kSlidingIndex + 1] = 2.5;
  s.slip.weight[kSlidingIndex + 2] = 1.0;
  s.slip.weight[kSlidingIndex + 3] = 0.5;
  s.slip.tension_weight[kSlidingIndex + 0] = 0.09;
  s.slip.tension_weight[kSlidingIndex + 1] = 0.075;
  s.slip.load_weight[kSlidingIndex + 0] = 0.03;
  s.slip.load_weight[kSlidingIndex + 1] = 0.025;
  return s;
}

TEST(DistributedSlip, LeastSquaresRecoversKnownWeightsAndCopies) {
  const TsmModelSpec truth = known_truth();
  const FitData d = synthetic(truth, 0.05, 11);
  const CopiesInData copies = copies_in_data(d);
  EXPECT_TRUE(copies.tension);
  EXPECT_TRUE(copies.load);
  TsmModelSpec s = truth;
  s.slip.weight.fill(1.0);
  s.slip.tension_weight.fill(0.0);
  s.slip.load_weight.fill(0.0);
  const double mse = solve_slip_weights(s, d);
  EXPECT_NEAR(std::sqrt(mse), 0.05, 0.005);  // at the noise
  for (std::size_t k = 0; k < truth.slip.basis_count(); ++k) {
    const std::size_t i = truth.slip.basis_index(k);
    EXPECT_NEAR(s.slip.weight[i], truth.slip.weight[i], 0.05) << slip_basis_name(i);
    EXPECT_NEAR(s.slip.tension_weight[i], truth.slip.tension_weight[i], 0.01) << slip_basis_name(i);
    EXPECT_NEAR(s.slip.load_weight[i], truth.slip.load_weight[i], 0.005) << slip_basis_name(i);
  }
}

// Two sheaths' capstans: each tendon's friction scales with its own
// tension, T1 = T + u/2 and T3 = T - u/2, so the friction has tension
// copies and drive copies (per N of u), of different sizes per direction.
TsmModelSpec capstan_truth() {
  TsmModelSpec s = known_truth();
  s.slip.load_copies = false;
  s.slip.load_weight.fill(0.0);
  s.slip.drive_copies = true;
  for (std::size_t i = 0; i < 10; ++i)
    s.slip.drive_weight[i] = 0.012 * s.slip.weight[i];
  s.slip.drive_weight[kSlidingIndex + 0] = 0.05;
  s.slip.drive_weight[kSlidingIndex + 1] = -0.04;
  return s;
}

TEST(DistributedSlip, LeastSquaresRecoversDriveCopies) {
  const TsmModelSpec truth = capstan_truth();
  const FitData d = synthetic(truth, 0.05, 13);
  EXPECT_TRUE(copies_in_data(d).drive);
  TsmModelSpec s = truth;
  s.slip.weight.fill(1.0);
  s.slip.tension_weight.fill(0.0);
  s.slip.drive_weight.fill(0.0);
  const double mse = solve_slip_weights(s, d);
  EXPECT_NEAR(std::sqrt(mse), 0.05, 0.005);
  for (std::size_t k = 0; k < truth.slip.basis_count(); ++k) {
    const std::size_t i = truth.slip.basis_index(k);
    EXPECT_NEAR(s.slip.weight[i], truth.slip.weight[i], 0.05) << slip_basis_name(i);
    EXPECT_NEAR(s.slip.drive_weight[i], truth.slip.drive_weight[i], 0.003) << slip_basis_name(i);
  }
}

TEST(DistributedSlip, DriveCopiesRoundTripThroughTheParamsFile) {
  const TsmModelSpec truth = capstan_truth();
  const TsmFrictionModel model(truth);
  const auto back = parse_model(model_to_yaml(model), "round trip");
  const auto* tsm = dynamic_cast<const TsmFrictionModel*>(back.get());
  ASSERT_NE(tsm, nullptr);
  EXPECT_TRUE(tsm->spec().slip.drive_copies);
  for (std::size_t k = 0; k < truth.slip.basis_count(); ++k) {
    const std::size_t i = truth.slip.basis_index(k);
    EXPECT_DOUBLE_EQ(tsm->spec().slip.drive_weight[i], truth.slip.drive_weight[i]);
  }
  // The same friction for the same motion, tension and drive.
  Motion m;
  m.x = 0.1, m.xd = 0.2, m.tension = 24.0, m.drive = -7.0;
  TsmFrictionModel a(truth), b(tsm->spec());
  a.reset(), b.reset();
  EXPECT_DOUBLE_EQ(a.step(m, 1e-3), b.step(m, 1e-3));
  TsmModelSpec bad = truth;
  bad.slip.drive_weight[0] = 1.5;
  EXPECT_THROW(validate(bad), std::invalid_argument);
}

// Two sheaths whose presliding follows each tendon's tension: element
// families per tendon (tendon_widths), the second tendon's break forces
// unlike the first's.
TsmModelSpec tendon_truth() {
  TsmModelSpec s;
  s.slip.enabled = true;
  s.slip.tendon_widths = true;
  s.slip.elements = 6;
  s.slip.width_min = 2e-3;
  s.slip.width_max = 0.15;
  s.slip.smoothing = 0.02;
  s.slip.stribeck_speed = 0.15;
  s.slip.tension_ref = 20.0;
  const double w[12] = {0.3, 0.8, 1.1, 0.5, 0.9, 0.4, 0.1, 0.5, 0.6, 1.4, 0.2, 0.7};
  for (std::size_t i = 0; i < 12; ++i)
    s.slip.weight[i] = w[i];
  s.slip.weight[kSlidingIndex + 0] = 2.0;
  s.slip.weight[kSlidingIndex + 1] = 1.8;
  return s;
}

// The fit's view of a sheath: the input's motion (the same multisine for
// every case), what `measured_inputs` adds at time t (tensions, the tip's
// angle), the friction from the truth with them, plus white noise.
template <class MeasuredInputs>
FitData sheath_data(const TsmModelSpec& truth, double noise, std::uint32_t seed,
                    MeasuredInputs measured_inputs) {
  FitData d;
  const double dt = 1e-3;
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0.0, noise);
  TsmFrictionModel model(truth);
  model.reset();
  for (std::size_t k = 0; k < 40000; ++k) {
    const double t = static_cast<double>(k) * dt;
    Motion m;
    m.t = t;
    m.x = 0.5 * std::sin(0.7 * t) + 0.15 * std::sin(2.9 * t + 1.0) + 0.02 * std::sin(11.0 * t);
    m.xd = 0.35 * std::cos(0.7 * t) + 0.435 * std::cos(2.9 * t + 1.0) + 0.22 * std::cos(11.0 * t);
    measured_inputs(t, m);
    d.measured.push_back(model.step(m, dt) + g(rng));
    d.motion.push_back(m);
    d.role.push_back(role_at(t));
  }
  d.radius_m = 0.01;
  return d;
}

// A sheath pair: the mean tension and the drive u measured; the drive
// reaches 2 T at times, so tendon 2 goes slack.
FitData tendon_data(const TsmModelSpec& truth, double noise, std::uint32_t seed) {
  return sheath_data(truth, noise, seed, [](double t, Motion& m) {
    m.tension = 20.0 + 4.0 * std::sin(0.13 * t + 0.5);
    m.drive = 40.0 * std::sin(0.21 * t) * std::sin(0.05 * t + 0.3);
  });
}

TEST(DistributedSlip, TendonWidthsScaleWithTheTensionAndASlackTendonCarriesNone) {
  TsmModelSpec s = tendon_truth();
  s.slip.weight[kSlidingIndex + 0] = s.slip.weight[kSlidingIndex + 1] = 0.0;
  const SlipKernel kernel(s.slip);
  SlipState st;
  SlipBasis b;
  // Tendon 1 at 40 N (twice the reference), tendon 2 slack (T - u/2 < 0).
  kernel.advance(st, 0.0, 0.0, 15.0, 50.0, std::nan(""), b);
  EXPECT_DOUBLE_EQ(b.scale[0], 2.0);
  EXPECT_DOUBLE_EQ(b.scale[1], 0.0);
  // A long stroke saturates every element: family 1 at twice its break
  // forces, family 2 at none.
  kernel.advance(st, 1.0, 1.0, 15.0, 50.0, std::nan(""), b);
  double level = 0.0;
  double family1 = 0.0;
  for (std::size_t i = 0; i < 6; ++i)
    family1 += s.slip.weight[i];
  EXPECT_NEAR(kernel.friction(b, 15.0, 50.0, 0.0, level), 2.0 * family1, 1e-12);
  for (std::size_t i = 6; i < 12; ++i)
    EXPECT_EQ(b.phi[i], 0.0);
  // The stiffness is the tension's own: from a reversal, the first element
  // takes twice the displacement to saturate at twice the tension.
  const double r0 = s.slip.width(0);
  SlipState a, c;
  kernel.advance(a, 0.0, 0.0, 20.0, 0.0, std::nan(""), b);  // both at the reference
  kernel.advance(c, 0.0, 0.0, 40.0, 0.0, std::nan(""), b);  // both at twice it
  kernel.advance(a, 1.5 * r0, 1.0, 20.0, 0.0, std::nan(""), b);
  EXPECT_DOUBLE_EQ(b.phi[0], 1.0);  // saturated at 1
  kernel.advance(c, 1.5 * r0, 1.0, 40.0, 0.0, std::nan(""), b);
  EXPECT_DOUBLE_EQ(b.phi[0], 1.5);  // still on its spring, limit 2
  // Without measured tensions the families are the plain elements.
  kernel.advance(a, 0.0, -1.0, std::nan(""), std::nan(""), std::nan(""), b);
  EXPECT_DOUBLE_EQ(b.scale[0], 1.0);
  EXPECT_DOUBLE_EQ(b.scale[1], 1.0);
}

// Least squares from all-ones weights, on data with 0.05 N of noise: the
// residual is the noise and every weight within 0.05 N of the truth's.
void expect_weights_recovered(const TsmModelSpec& truth, const FitData& d) {
  TsmModelSpec s = truth;
  s.slip.weight.fill(1.0);
  EXPECT_NEAR(std::sqrt(solve_slip_weights(s, d)), 0.05, 0.005);
  for (std::size_t k = 0; k < truth.slip.basis_count(); ++k) {
    const std::size_t i = truth.slip.basis_index(k);
    EXPECT_NEAR(s.slip.weight[i], truth.slip.weight[i], 0.05) << slip_basis_name(i);
  }
}

TEST(DistributedSlip, LeastSquaresRecoversTendonWidthsThatCopiesCannotMimic) {
  const TsmModelSpec truth = tendon_truth();
  const FitData d = tendon_data(truth, 0.05, 17);
  expect_weights_recovered(truth, d);
  // One family with both copies (per-tendon break forces, fixed widths)
  // over the same widths stays well above the noise: the widths themselves
  // follow the tension, and a slack tendon's elements lose their state.
  TsmModelSpec plain = truth;
  plain.slip.tendon_widths = false;
  plain.slip.elements = 12;
  plain.slip.tension_copies = true;
  plain.slip.drive_copies = true;
  const double plain_mse = solve_slip_weights(plain, d);
  EXPECT_GT(std::sqrt(plain_mse), 3.0 * 0.05);
}

TEST(DistributedSlip, TendonWidthsRoundTripThroughTheParamsFileAndTheState) {
  const TsmModelSpec truth = tendon_truth();
  const TsmFrictionModel model(truth);
  const std::string yaml = model_to_yaml(model);
  EXPECT_NE(yaml.find("tendon_widths: true"), std::string::npos) << yaml;
  const auto back = parse_model(yaml, "round trip");
  const auto* tsm = dynamic_cast<const TsmFrictionModel*>(back.get());
  ASSERT_NE(tsm, nullptr);
  EXPECT_TRUE(tsm->spec().slip.tendon_widths);
  EXPECT_EQ(tsm->spec().slip.basis_count(), 16u);
  // The same friction along a motion, and a restored state continues alike.
  TsmFrictionModel a(truth), b(tsm->spec());
  a.reset(), b.reset();
  const FitData d = tendon_data(truth, 0.0, 1);
  DynamicsState mid;
  for (std::size_t k = 0; k < 3000; ++k) {
    EXPECT_DOUBLE_EQ(a.step(d.motion[k], 1e-3), b.step(d.motion[k], 1e-3));
    if (k == 1500) {
      ASSERT_TRUE(a.save_state(mid));
    }
  }
  const double next = a.step(d.motion[3000], 1e-3);
  b.restore_state(mid);
  for (std::size_t k = 1501; k < 3000; ++k)
    b.step(d.motion[k], 1e-3);
  EXPECT_DOUBLE_EQ(b.step(d.motion[3000], 1e-3), next);
  // Two families of 13 do not fit the state.
  std::string bad = yaml;
  bad.replace(bad.find("elements: 6"), 11, "elements: 13");
  EXPECT_THROW(parse_model(bad, "bad.yaml"), ParamsError);
}

// A stuck sheath holds the friction it had when the input stopped. With
// tanh(xd / smoothing) the Coulomb functions drop their share when the
// input stops (the world's palpation holds: ~2 N at every stop); as a play
// of the narrowest element's width they keep it, until the input moves back
// by that width. An option of the model (`coulomb_play: true` in a params
// file); the preset keeps tanh.
TEST(DistributedSlip, CoulombPlayHoldsItsFrictionAtRest) {
  TsmModelSpec s = elements_only(4, 1e-3, 0.05, {1.0, 1.0, 1.0, 1.0});
  s.slip.weight[kSlidingIndex + 0] = 3.0;  // coulomb +
  s.slip.weight[kSlidingIndex + 1] = 2.0;  // coulomb -
  s.slip.smoothing = 0.01;
  const auto friction_after = [&](bool play, double x_back) {
    TsmModelSpec p = s;
    p.slip.coulomb_play = play;
    TsmFrictionModel m(p);
    m.reset();
    Motion mo;
    double f = 0.0;
    // Slide 0.2 rad positive at 0.5 rad/s, then stop, hold 1 s, then move
    // back by x_back and hold again.
    for (int k = 0; k <= 400; ++k) {
      mo.t = k * 1e-3, mo.x = 5e-4 * k, mo.xd = 0.5;
      f = m.step(mo, 1e-3);
    }
    EXPECT_NEAR(f, 4.0 + 3.0 * std::tanh(0.5 / 0.01), 1e-9);
    mo.xd = 0.0;
    for (int k = 0; k < 1000; ++k) {
      mo.t += 1e-3;
      f = m.step(mo, 1e-3);
    }
    mo.t += 1e-3, mo.x -= x_back;
    m.step(mo, 1e-3);
    mo.t += 1e-3;
    return m.step(mo, 1e-3);
  };
  // At rest: tanh drops the Coulomb share, the play keeps it.
  EXPECT_NEAR(friction_after(false, 0.0), 4.0, 1e-9);
  EXPECT_NEAR(friction_after(true, 0.0), 7.0, 1e-9);
  // Two of the narrowest widths back: the play at its negative level (as the
  // narrowest element), the wider elements part of the way.
  double elements = 0.0;
  for (std::size_t i = 0; i < 4; ++i)
    elements += std::max(-1.0, 1.0 - 2e-3 / s.slip.width(i));
  EXPECT_NEAR(friction_after(true, 2e-3), elements - 2.0, 1e-9);
  // The params file carries it (only where it is on) and names a bad value.
  TsmModelSpec on = s;
  on.slip.coulomb_play = true;
  const std::string yaml = model_to_yaml(TsmFrictionModel(on));
  EXPECT_NE(yaml.find("coulomb_play: true"), std::string::npos) << yaml;
  const auto back_model = parse_model(yaml, "round trip");
  EXPECT_TRUE(dynamic_cast<const TsmFrictionModel&>(*back_model).spec().slip.coulomb_play);
  EXPECT_EQ(model_to_yaml(TsmFrictionModel(s)).find("coulomb_play"), std::string::npos);
  std::string bad = yaml;
  bad.replace(bad.find("coulomb_play: true"), 18, "coulomb_play: 3");
  EXPECT_THROW(parse_model(bad, "bad.yaml"), ParamsError);
}

TEST(DistributedSlip, SeparableFitFindsTheSpreadFromTheCatalogStart) {
  const TsmModelSpec truth = capstan_truth();
  const FitData d = synthetic(truth, 0.05, 12);
  FitOptions o;
  const auto r = identify(TsmFrictionModel(distributed_spec()), d, o);
  const auto* fitted = dynamic_cast<const TsmFrictionModel*>(r.model.get());
  ASSERT_NE(fitted, nullptr);
  EXPECT_TRUE(fitted->spec().slip.tension_copies);
  EXPECT_TRUE(fitted->spec().slip.drive_copies);
  // Within 10 % of the noise floor on train, and on validation too.
  EXPECT_LT(r.train_rmse, 1.1 * 0.05);
  double sse = 0.0, n = 0.0;
  for (std::size_t i = 0; i < d.size(); ++i)
    if (d.role[i] == SampleRole::kValidation) {
      const double e = r.simulated[i] - d.measured[i];
      sse += e * e, n += 1.0;
    }
  EXPECT_LT(std::sqrt(sse / n), 1.15 * 0.05);
}

}  // namespace
}  // namespace tsmh::estimator

namespace tsmh::estimator {
namespace {

// Slip driven from the tip: six elements on the input angle, a Coulomb
// level, and a distal family of four halfway to the distal angle.
TsmModelSpec distal_truth() {
  TsmModelSpec s = elements_only(6, 2e-3, 0.15, {0.5, 0.9, 1.2, 0.6, 0.8, 0.4});
  s.slip.weight[kSlidingIndex + 0] = 1.5;
  s.slip.weight[kSlidingIndex + 1] = 1.2;
  s.slip.smoothing = 0.02;
  s.slip.distal_elements = 4;
  s.slip.distal_position = 0.5;
  const double v[4] = {0.7, 1.5, 0.4, 0.9};
  for (std::size_t j = 0; j < 4; ++j)
    s.slip.weight[kDistalIndex + j] = v[j];
  return s;
}

// The input pulley still while the tip moves (its load changes, the tendon
// stretches): a model driven by x_in alone keeps its friction, the distal
// family turns by its drive a (x_out - x_in).
TEST(DistributedSlip, DistalFamilyTurnsWhenTheTipMovesAlone) {
  const TsmModelSpec s = distal_truth();
  TsmModelSpec rigid = s;
  rigid.slip.distal_elements = 0;
  const auto friction_after = [](const TsmModelSpec& spec, double tip_back, double* held) {
    TsmFrictionModel m(spec);
    m.reset();
    Motion mo;
    double f = 0.0;
    // Both ends slide 0.4 rad positive (every element saturates), then stop.
    for (int k = 0; k <= 800; ++k) {
      mo.t = k * 1e-3, mo.x = 5e-4 * k, mo.x_out = mo.x, mo.xd = 0.5;
      f = m.step(mo, 1e-3);
    }
    mo.xd = 0.0;
    mo.t += 1e-3;
    *held = m.step(mo, 1e-3);
    // The tip moves back alone.
    for (int k = 1; k <= 100; ++k) {
      mo.t += 1e-3, mo.x_out = 0.4 - tip_back * k / 100.0;
      f = m.step(mo, 1e-3);
    }
    return f;
  };
  double held = 0.0, held_rigid = 0.0;
  const double f = friction_after(s, 0.02, &held);
  const double f_rigid = friction_after(rigid, 0.02, &held_rigid);
  double proximal = 0.0, distal = 0.0;
  for (std::size_t i = 0; i < 6; ++i)
    proximal += s.slip.weight[i];
  for (std::size_t j = 0; j < 4; ++j)
    distal += s.slip.weight[kDistalIndex + j] *
              std::clamp(1.0 - 0.5 * 0.02 / s.slip.distal_width(j), -1.0, 1.0);
  EXPECT_NEAR(held, proximal + 3.5, 1e-9);  // saturated; at rest the Coulomb share is 0
  EXPECT_NEAR(f, proximal + distal, 1e-9);
  EXPECT_LT(f, held - 1.0);
  EXPECT_NEAR(f_rigid, held_rigid, 1e-12);  // x_in alone cannot see it
}

// Without a joint encoder (x_out NaN) the family follows x_in, a rigid
// tendon: the same friction as its elements on the input angle. When the
// encoder appears (x_out offset by the stretch) the family re-anchors
// instead of stepping; a saved state continues alike.
TEST(DistributedSlip, DistalFamilyFallsBackToTheInputAndReanchors) {
  const TsmModelSpec s = distal_truth();
  TsmModelSpec base = s;
  base.slip.distal_elements = 0;
  std::vector<double> v;
  for (std::size_t j = 0; j < 4; ++j)
    v.push_back(s.slip.weight[kDistalIndex + j]);
  TsmModelSpec alone = elements_only(4, 2e-3, 0.15, v);
  TsmFrictionModel a(s), b(base), c(alone);
  a.reset(), b.reset(), c.reset();
  const auto x = wandering_angle(4000, 1e-3);
  Motion mo;
  for (std::size_t k = 0; k < x.size(); ++k) {
    mo.t = static_cast<double>(k) * 1e-3;
    mo.x = x[k];
    mo.xd = k ? (x[k] - x[k - 1]) / 1e-3 : 0.0;
    const double fa = a.step(mo, 1e-3);
    EXPECT_NEAR(fa, b.step(mo, 1e-3) + c.step(mo, 1e-3), 1e-9) << k;
  }
  // The encoder appears 0.05 rad away while the input holds: no step.
  mo.xd = 0.0;
  mo.t += 1e-3;
  const double before = a.step(mo, 1e-3);
  mo.t += 1e-3;
  mo.x_out = mo.x + 0.05;
  EXPECT_DOUBLE_EQ(a.step(mo, 1e-3), before);
  DynamicsState saved;
  ASSERT_TRUE(a.save_state(saved));
  TsmFrictionModel d(s);
  d.reset();
  d.restore_state(saved);
  for (int k = 1; k <= 50; ++k) {
    mo.t += 1e-3, mo.x_out += 2e-4;
    EXPECT_DOUBLE_EQ(a.step(mo, 1e-3), d.step(mo, 1e-3));
  }
  // It then follows x_out: the input last moved negative, the tip moving
  // positive turns the distal family.
  EXPECT_GT(a.friction(), before + 1.0);
}

// The tip moves apart from the input by a stretch that varies on its own
// (tip loads).
FitData distal_data(const TsmModelSpec& truth, double noise, std::uint32_t seed) {
  return sheath_data(truth, noise, seed, [](double t, Motion& m) {
    m.x_out = m.x + 0.06 * std::sin(0.37 * t) + 0.02 * std::sin(1.7 * t + 0.4);
  });
}

TEST(DistributedSlip, LeastSquaresRecoversTheDistalFamily) {
  const TsmModelSpec truth = distal_truth();
  const FitData d = distal_data(truth, 0.05, 23);
  expect_weights_recovered(truth, d);
  // Elements on the input angle alone stay well above the noise.
  TsmModelSpec rigid = truth;
  rigid.slip.distal_elements = 0;
  EXPECT_GT(std::sqrt(solve_slip_weights(rigid, d)), 3.0 * 0.05);
}

TEST(DistributedSlip, DistalFamilyRoundTripsThroughTheParamsFile) {
  const TsmModelSpec truth = distal_truth();
  const std::string yaml = model_to_yaml(TsmFrictionModel(truth));
  EXPECT_NE(yaml.find("distal_elements: 4"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("distal_position: 0.5"), std::string::npos) << yaml;
  const auto back = parse_model(yaml, "round trip");
  const auto& tsm = dynamic_cast<const TsmFrictionModel&>(*back);
  EXPECT_EQ(tsm.spec().slip.distal_elements, 4);
  EXPECT_EQ(tsm.spec().slip.basis_count(), 14u);
  const FitData d = distal_data(truth, 0.0, 1);
  TsmFrictionModel a(truth), b(tsm.spec());
  a.reset(), b.reset();
  for (std::size_t k = 0; k < 3000; ++k)
    EXPECT_DOUBLE_EQ(a.step(d.motion[k], 1e-3), b.step(d.motion[k], 1e-3));
  // The parameters carry the count (fixed) and the weights d1 .. d4.
  const auto params = TsmFrictionModel(truth).parameters();
  const auto named = [&](const std::string& n) {
    return std::find_if(params.begin(), params.end(),
                        [&](const Parameter& p) { return p.name == n; }) != params.end();
  };
  EXPECT_TRUE(named("distributed_slip.distal_elements"));
  EXPECT_TRUE(named("distributed_slip.weights.d4"));
  // Off, the file has no such key; bad values are named.
  TsmModelSpec off = truth;
  off.slip.distal_elements = 0;
  EXPECT_EQ(model_to_yaml(TsmFrictionModel(off)).find("distal"), std::string::npos);
  const auto names_field = [&](const std::string& from, const std::string& to,
                               const std::string& field) {
    std::string bad = yaml;
    bad.replace(bad.find(from), from.size(), to);
    try {
      parse_model(bad, "bad.yaml");
      ADD_FAILURE() << "accepted " << to;
    } catch (const ParamsError& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  names_field("distal_position: 0.5", "distal_position: 1.5", "distributed_slip.distal_position");
  names_field("distal_elements: 4", "distal_elements: 13", "distributed_slip.distal_elements");
  TsmModelSpec negative = truth;
  negative.slip.weight[kDistalIndex + 2] = -0.1;
  try {
    validate(negative);
    ADD_FAILURE() << "a negative distal break force was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("weights.d3"), std::string::npos) << e.what();
  }
}

// Two places along the sheath: four elements at a quarter of the way to
// the distal angle, four at three quarters (a stretch that is not uniform).
TsmModelSpec two_position_truth() {
  TsmModelSpec s = distal_truth();
  s.slip.distal_elements = 8;
  s.slip.distal_position = 0.25;
  s.slip.distal_position2 = 0.75;
  const double v[8] = {0.7, 1.5, 0.4, 0.9, 1.1, 0.3, 1.3, 0.6};
  for (std::size_t j = 0; j < 8; ++j)
    s.slip.weight[kDistalIndex + j] = v[j];
  return s;
}

// The two sub-families are exactly two single-position families side by
// side, through a change of source too (the second one's last angle is
// derived from the first's, not stored).
TEST(DistributedSlip, TwoDistalPositionsAreTwoFamiliesSideBySide) {
  const TsmModelSpec s = two_position_truth();
  TsmModelSpec first = s, second = s;
  first.slip.distal_elements = 4;
  first.slip.distal_position2 = 0.0;
  second.slip.distal_elements = 4;
  second.slip.distal_position = 0.75;
  second.slip.distal_position2 = 0.0;
  for (std::size_t j = 0; j < 4; ++j)
    second.slip.weight[kDistalIndex + j] = s.slip.weight[kDistalIndex + 4 + j];
  // The second model's proximal and sliding parts would count twice.
  TsmModelSpec base = s;
  base.slip.distal_elements = 0;
  base.slip.distal_position2 = 0.0;
  TsmFrictionModel a(s), b(first), c(second), p(base);
  a.reset(), b.reset(), c.reset(), p.reset();
  const FitData d = distal_data(s, 0.0, 1);
  for (std::size_t k = 0; k < 6000; ++k) {
    Motion m = d.motion[k];
    if (k >= 2000 && k < 3000) m.x_out = std::numeric_limits<double>::quiet_NaN();
    const double fa = a.step(m, 1e-3);
    EXPECT_NEAR(fa, b.step(m, 1e-3) + c.step(m, 1e-3) - p.step(m, 1e-3), 1e-9) << k;
  }
}

TEST(DistributedSlip, LeastSquaresRecoversTwoDistalPositionsThatOneCannot) {
  const TsmModelSpec truth = two_position_truth();
  const FitData d = distal_data(truth, 0.05, 29);
  expect_weights_recovered(truth, d);
  // One position, anywhere along the sheath and with as many elements,
  // stays well above the noise.
  for (int step = 1; step <= 20; ++step) {
    TsmModelSpec one = truth;
    one.slip.distal_position = 0.05 * step;
    one.slip.distal_position2 = 0.0;
    EXPECT_GT(std::sqrt(solve_slip_weights(one, d)), 2.0 * 0.05) << one.slip.distal_position;
  }
}

TEST(DistributedSlip, TwoDistalPositionsRoundTripThroughTheParamsFile) {
  const TsmModelSpec truth = two_position_truth();
  const std::string yaml = model_to_yaml(TsmFrictionModel(truth));
  EXPECT_NE(yaml.find("distal_position2: 0.75"), std::string::npos) << yaml;
  const auto back = parse_model(yaml, "round trip");
  const auto& tsm = dynamic_cast<const TsmFrictionModel&>(*back);
  EXPECT_EQ(tsm.spec().slip.distal_position2, 0.75);
  const FitData d = distal_data(truth, 0.0, 1);
  TsmFrictionModel a(truth), b(tsm.spec());
  a.reset(), b.reset();
  for (std::size_t k = 0; k < 3000; ++k)
    EXPECT_DOUBLE_EQ(a.step(d.motion[k], 1e-3), b.step(d.motion[k], 1e-3));
  // One position writes no such key.
  EXPECT_EQ(model_to_yaml(TsmFrictionModel(distal_truth())).find("distal_position2"),
            std::string::npos);
  const auto names_field = [&](const std::string& from, const std::string& to) {
    std::string bad = yaml;
    bad.replace(bad.find(from), from.size(), to);
    try {
      parse_model(bad, "bad.yaml");
      ADD_FAILURE() << "accepted " << to;
    } catch (const ParamsError& e) {
      EXPECT_NE(std::string(e.what()).find("distributed_slip.distal_position2"), std::string::npos)
          << e.what();
    }
  };
  names_field("distal_position2: 0.75", "distal_position2: 1.5");
  names_field("distal_position2: 0.75", "distal_position2: 0.25");
  names_field("distal_position2: 0.75", "distal_position2: nope");
  TsmModelSpec one_element = truth;
  one_element.slip.distal_elements = 1;
  try {
    validate(one_element);
    ADD_FAILURE() << "two positions with one distal element were accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("distal_position2"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace tsmh::estimator
