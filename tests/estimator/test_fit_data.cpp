// Preparing data for identification: refusals that name file, line/sample and
// column; the train/validation split; error metrics; the noise-floor
// estimate; the synthetic generator; normalised parameter coordinates.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

#include "estimator/fit_data.hpp"
#include "estimator/fit_metrics.hpp"
#include "estimator/parameter_map.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

// A short, quick recording of a 0.5 Hz sine with a friction-like signal.
Recording sine_recording(double duration = 10.0, double amplitude = 0.8) {
  Recording r;
  r.source = "sine.csv";
  r.radius_m = 0.01;
  const double w = 2.0 * std::numbers::pi * 0.5;
  for (int i = 0; i <= static_cast<int>(duration * 1000); ++i) {
    const double t = i * 1e-3;
    r.t.push_back(t);
    r.x_in.push_back(amplitude * std::sin(w * t));
    r.tau_out.push_back(0.02);
    r.tau_in.push_back(0.02 + 0.01 * 9.0 * std::tanh(5.0 * std::cos(w * t)));
  }
  return r;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const DataError& e) {
    return e.what();
  }
  return "";
}

TEST(FitData, RefusesMissingColumnsNamingThem) {
  Recording r = sine_recording();
  r.tau_out.clear();
  const auto msg = message_of([&] { prepare_fit_data(r); });
  EXPECT_NE(msg.find("sine.csv"), std::string::npos) << msg;
  EXPECT_NE(msg.find("tau_out"), std::string::npos) << msg;
  r = sine_recording();
  r.radius_m = std::nan("");
  EXPECT_NE(message_of([&] { prepare_fit_data(r); }).find("radius"), std::string::npos);
}

TEST(FitData, RefusesNonFiniteSamplesNamingColumnAndSample) {
  Recording r = sine_recording();
  r.tau_in[1234] = std::nan("");
  const auto msg = message_of([&] { prepare_fit_data(r); });
  EXPECT_NE(msg.find("tau_in"), std::string::npos) << msg;
  EXPECT_NE(msg.find("sample 1235"), std::string::npos) << msg;
}

TEST(FitData, RefusesNaNInCsvNamingTheLine) {
  const fs::path p =
      fs::temp_directory_path() / ("tsmh_fit_nan_" + std::to_string(::getpid()) + ".csv");
  {
    std::ofstream f(p);
    f << "# radius_m: 0.01\nt,x_in,tau_in,tau_out\n0,0,0,0\n0.001,nan,0,0\n";
  }
  const auto msg = message_of([&] { read_recording_csv(p, std::nullopt, {}); });
  fs::remove(p);
  EXPECT_NE(msg.find(":4"), std::string::npos) << msg;  // line 4 of the file
  EXPECT_NE(msg.find("x_in"), std::string::npos) << msg;
}

TEST(FitData, RefusesTimeNotIncreasing) {
  Recording r = sine_recording();
  r.t[500] = r.t[499];
  const auto msg = message_of([&] { prepare_fit_data(r); });
  EXPECT_NE(msg.find("'t'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("sample 501"), std::string::npos) << msg;
}

TEST(FitData, RefusesTooShort) {
  const auto msg = message_of([&] { prepare_fit_data(sine_recording(2.0)); });
  EXPECT_NE(msg.find("too short"), std::string::npos) << msg;
}

TEST(FitData, RefusesNoMotion) {
  // At rest, only encoder noise of one quantum.
  Recording r = sine_recording(10.0, 0.0);
  for (std::size_t i = 0; i < r.size(); ++i)
    r.x_in[i] = (i % 7 == 0) ? 1.5e-4 : 0.0;
  const auto msg = message_of([&] { prepare_fit_data(r); });
  EXPECT_NE(msg.find("no motion"), std::string::npos) << msg;
  EXPECT_NE(msg.find("x_in"), std::string::npos) << msg;
  // Moving, but never reversing (a slow ramp): no hysteresis to identify.
  Recording ramp = sine_recording(10.0, 0.0);
  for (std::size_t i = 0; i < ramp.size(); ++i)
    ramp.x_in[i] = 0.1 * ramp.t[i];
  EXPECT_NE(message_of([&] { prepare_fit_data(ramp); }).find("reversals"), std::string::npos);
}

TEST(FitData, SplitsIntoAlternateBlocksAfterWarmUp) {
  const FitData d = prepare_fit_data(sine_recording(20.0), {.block_s = 2.0, .warmup_s = 0.5});
  EXPECT_EQ(d.block_s, 2.0);
  EXPECT_NEAR(d.reversals, 20, 1);  // 0.5 Hz sine over 20 s: xd = 0 every 1 s
  for (std::size_t i = 0; i < d.size(); ++i) {
    const double t = d.motion[i].t;
    if (t < 0.5) {
      EXPECT_EQ(d.role[i], SampleRole::kIgnored);
    } else {
      const int block = static_cast<int>(std::floor((t - 0.5) / 2.0));
      EXPECT_EQ(d.role[i], block % 2 == 0 ? SampleRole::kTrain : SampleRole::kValidation) << t;
    }
  }
  const double train = static_cast<double>(d.count(SampleRole::kTrain));
  const double val = static_cast<double>(d.count(SampleRole::kValidation));
  EXPECT_NEAR(train / val, 1.0, 0.3);
  // A short record gets shorter blocks: at least three of each.
  const FitData s = prepare_fit_data(sine_recording(8.0));
  EXPECT_LE(s.block_s, (8.0 - 0.5) / 6.0 + 1e-12);
}

TEST(ErrorMetrics, HandValues) {
  const std::vector<double> y = {1.0, 2.0, 3.0, 4.0};
  const std::vector<double> f = {1.5, 2.0, 2.0, 4.0};  // e = -0.5, 0, 1, 0
  const auto m = error_metrics(y, f, [](std::size_t) { return true; });
  EXPECT_NEAR(m.rmse, std::sqrt(1.25 / 4.0), 1e-12);
  EXPECT_NEAR(m.p2p, 1.5, 1e-12);
  EXPECT_NEAR(m.bias, 0.125, 1e-12);
  // ||y - mean|| = sqrt(5); ||e|| = sqrt(1.25)
  EXPECT_NEAR(m.fit_percent, 100.0 * (1.0 - std::sqrt(1.25 / 5.0)), 1e-9);
  const auto some = error_metrics(y, f, [](std::size_t i) { return i >= 2; });
  EXPECT_EQ(some.samples, 2U);
  EXPECT_NEAR(some.p2p, 1.0, 1e-12);
}

TEST(ErrorMetrics, NoiseFloorRecoversWhiteNoiseOnSmoothSignal) {
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.4);
  std::vector<double> y;
  for (int i = 0; i < 40000; ++i)
    y.push_back(9.0 * std::tanh(4.0 * std::sin(3.0 * i * 1e-3)) + noise(rng));
  EXPECT_NEAR(noise_floor(y), 0.4, 0.02);
}

TEST(ErrorMetrics, RegimesLocateAnErrorOnNegativeVelocity) {
  const FitData d = prepare_fit_data(sine_recording(20.0));
  std::vector<double> model = d.measured;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d.motion[i].xd < -0.3) model[i] += 1.0;  // wrong only when moving backwards
  }
  const auto regimes = regime_errors(d, model, SampleRole::kValidation);
  double pos = 0.0, neg = 0.0;
  for (const auto& r : regimes) {
    if (r.name == "positive_velocity") pos = r.metrics.rmse;
    if (r.name == "negative_velocity") {
      neg = r.metrics.rmse;
      EXPECT_GT(r.concentration, 1.5);
      EXPECT_LT(r.mean_error, 0.0);  // the model is above the measurement there
    }
  }
  EXPECT_LT(pos, 1e-9);
  EXPECT_GT(neg, 0.8);
}

TEST(Synthetic, SensorsAsConfiguredAndDeterministic) {
  const TsmFrictionModel truth(paper_spec());
  SyntheticConfig c;
  c.duration_s = 10.0;
  c.seed = 5;
  const auto a = make_synthetic(truth, c);
  const auto b = make_synthetic(truth, c);
  ASSERT_EQ(a.recording.size(), 10001U);
  EXPECT_EQ(a.recording.tau_in, b.recording.tau_in);
  EXPECT_EQ(a.recording.x_in, b.recording.x_in);
  c.seed = 6;
  EXPECT_NE(make_synthetic(truth, c).recording.tau_in, a.recording.tau_in);
  // Encoder quantisation and the amplitude.
  double peak = 0.0;
  for (double x : a.recording.x_in) {
    const double k = x / c.quantum;
    EXPECT_NEAR(k, std::round(k), 1e-6);
    peak = std::max(peak, std::fabs(x));
  }
  EXPECT_NEAR(peak, c.amplitude_rad, 0.01);
  // Measured F = true F + noise of std sqrt(2) 0.003 / 0.01.
  const auto f = a.recording.measured_friction();
  double s2 = 0.0;
  for (std::size_t i = 0; i < f.size(); ++i)
    s2 += (f[i] - a.true_friction[i]) * (f[i] - a.true_friction[i]);
  EXPECT_NEAR(std::sqrt(s2 / static_cast<double>(f.size())), std::sqrt(2.0) * 0.3, 0.02);
  EXPECT_NEAR(noise_floor(f), std::sqrt(2.0) * 0.3, 0.03);
}

TEST(ParameterMap, RoundTripsEachScaleAndSkipsFixed) {
  const TsmFrictionModel m(paper_spec());
  const auto params = m.parameters();
  const ParameterMap map(params);
  std::size_t free = 0;
  for (const auto& p : params)
    free += p.fixed ? 0 : 1;
  ASSERT_EQ(map.size(), free);
  for (std::size_t k = 0; k < map.size(); ++k) {
    const auto& fp = map.free()[k];
    EXPECT_NE(fp.name, "core.gamma");
    EXPECT_NE(fp.name, "core.n");
    for (double u : {0.0, 0.1, 0.5, 0.93, 1.0}) {
      const double v = map.from_unit(k, u);
      EXPECT_GE(v, fp.lower);
      EXPECT_LE(v, fp.upper);
      EXPECT_NEAR(map.to_unit(k, v), u, 1e-9) << fp.name;
    }
  }
  // theta spans four decades: log scale, so u = 0.5 is the geometric mean.
  for (std::size_t k = 0; k < map.size(); ++k) {
    if (map.free()[k].name == "core.theta") {
      EXPECT_EQ(map.free()[k].scale, ParameterScale::kLog);
      EXPECT_NEAR(map.from_unit(k, 0.5), std::sqrt(0.1 * 1000.0), 1e-9);
    }
  }
  std::vector<double> values;
  map.to_values(map.to_unit(map.template_values()), values);
  for (std::size_t i = 0; i < values.size(); ++i)
    EXPECT_NEAR(values[i], params[i].value, 1e-9 * (1.0 + std::fabs(params[i].value)));
}

}  // namespace
}  // namespace tsmh::estimator
