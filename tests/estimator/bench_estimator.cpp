// One estimator step for one joint, differentiation included: the work the
// haptic loop does per joint per tick, beside its parts: the model's step,
// the plain differentiator and the differentiator with its corrections (the
// one the estimator runs). At the end it prints the step's median over the
// model's plus each differentiator's (the cost target is a step within
// 1.15x the model plus the differentiator).
// Measured figures and what bounds them: docs/friction-model.md, "Cost";
// BM_EstimatorStepWithoutHindsight prints the cost of the hindsight correction.
// Run: build/bin/bench_estimator (or scripts/bench estimator).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <map>
#include <numbers>
#include <string>
#include <vector>

#include "estimator/distal_estimator.hpp"
#include "estimator/tsm_model.hpp"

namespace {

using namespace tsmh::estimator;

struct Samples {
  std::vector<double> t, x, tau;
};

Samples encoder_samples(std::size_t n) {
  Samples s;
  const double q = 2.0 * std::numbers::pi / 40960.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * 1e-3;
    s.t.push_back(t);
    // Multi-sine: reversals, both directions, varying acceleration.
    const double x = 0.6 * std::sin(2 * std::numbers::pi * 0.4 * t) +
                     0.2 * std::sin(2 * std::numbers::pi * 1.3 * t);
    s.x.push_back(std::round(x / q) * q);
    s.tau.push_back(0.15 * std::sin(2 * std::numbers::pi * 0.7 * t));
  }
  return s;
}

// One estimator step per iteration over the samples, repeated with a time
// offset so that time keeps increasing.
void run_estimator(benchmark::State& state, const Samples& s,
                   const CorrectionsConfig& corrections = {},
                   const TsmModelSpec& spec = paper_spec()) {
  DistalTorqueEstimator est(std::make_unique<TsmFrictionModel>(spec), 0.01, {},
                            StartState::kFreeTip, corrections);
  std::size_t i = 0;
  double t_offset = 0.0;
  for (auto _ : state) {
    // Both tensions, as haptic-server passes them (tau_in = R (T1 - T3)).
    const double t1 = 20.0 + 50.0 * s.tau[i], t3 = 20.0 - 50.0 * s.tau[i];
    const auto e = est.update_tensions(s.t[i] + t_offset, s.x[i], t1, t3);
    benchmark::DoNotOptimize(e);
    if (++i == s.t.size()) i = 0, t_offset += 100.0;
  }
  // The hindsight correction steps the model again after a corrected
  // sample: its share of the mean time per step.
  state.counters["resteps_per_step"] = benchmark::Counter(
      static_cast<double>(est.hindsight_resteps()), benchmark::Counter::kAvgIterations);
}

void BM_EstimatorStep(benchmark::State& state) {
  run_estimator(state, encoder_samples(1 << 16));
}
BENCHMARK(BM_EstimatorStep)
    ->Repetitions(15)
    ->ReportAggregatesOnly(true)
    ->DisplayAggregatesOnly(true);

// The same without the hindsight correction: what the correction costs,
// beside the figure above.
void BM_EstimatorStepWithoutHindsight(benchmark::State& state) {
  run_estimator(state, encoder_samples(1 << 16), {.hindsight = {.lag = 0.0}});
}
BENCHMARK(BM_EstimatorStepWithoutHindsight)
    ->Repetitions(15)
    ->ReportAggregatesOnly(true)
    ->DisplayAggregatesOnly(true);

// Strokes at 1.2 rad/s joined by 60 ms reversals (the jerk steps at each
// reversal's ends arm the differentiator's cruise hypothesis for 1 s, so it
// runs on most samples): the estimator's cost while the cruise test is
// armed, beside the smooth motion above, where it never is.
Samples reversal_samples(std::size_t n) {
  Samples s;
  const double q = 2.0 * std::numbers::pi / 40960.0;
  const double speed = 1.2, stroke_s = 1.0, reversal_s = 0.06;
  double x = 0.0, direction = 1.0, phase = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * 1e-3;
    s.t.push_back(t);
    s.x.push_back(std::round(x / q) * q);
    s.tau.push_back(0.15 * std::sin(2 * std::numbers::pi * 0.7 * t));
    const double v =
        phase < stroke_s
            ? direction * speed
            : direction * speed * std::cos(std::numbers::pi * (phase - stroke_s) / reversal_s);
    x += v * 1e-3;
    phase += 1e-3;
    if (phase >= stroke_s + reversal_s) phase = 0.0, direction = -direction;
  }
  return s;
}

void BM_EstimatorStepReversals(benchmark::State& state) {
  run_estimator(state, reversal_samples(1 << 16));
}
BENCHMARK(BM_EstimatorStepReversals)
    ->Repetitions(15)
    ->ReportAggregatesOnly(true)
    ->DisplayAggregatesOnly(true);

// The distributed-slip model at its largest deployed form: 14 elements,
// the sliding functions, tension and load copies (distributed_slip.hpp).
TsmModelSpec distributed_with_copies() {
  TsmModelSpec s = distributed_spec();
  s.slip.tension_copies = true;
  s.slip.load_copies = true;
  for (std::size_t i = 0; i < kMaxSlipBasis; ++i) {
    s.slip.tension_weight[i] = 0.01 * s.slip.weight[i];
    s.slip.load_weight[i] = 0.005 * s.slip.weight[i];
  }
  return s;
}

void BM_EstimatorStepDistributed(benchmark::State& state) {
  run_estimator(state, encoder_samples(1 << 16), {}, distributed_with_copies());
}
BENCHMARK(BM_EstimatorStepDistributed)
    ->Repetitions(15)
    ->ReportAggregatesOnly(true)
    ->DisplayAggregatesOnly(true);

void model_step_only(benchmark::State& state, const TsmModelSpec& spec) {
  TsmFrictionModel model(spec);
  std::vector<Motion> m;
  for (int i = 0; i < 4096; ++i) {
    const double t = i * 1e-3, w = 2 * std::numbers::pi * 0.5;
    const double xdd = -0.8 * w * w * std::sin(w * t);
    m.push_back({t, 0.8 * std::sin(w * t), 0.8 * w * std::cos(w * t), xdd, sign_of(xdd), 10.0,
                 10.0 * std::sin(0.3 * w * t), 20.0});
  }
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(model.step(m[i], 1e-3));
    i = (i + 1) & 4095;
  }
}

void BM_ModelStepOnly(benchmark::State& state) {
  model_step_only(state, paper_spec());
}
BENCHMARK(BM_ModelStepOnly)
    ->Repetitions(15)
    ->ReportAggregatesOnly(true)
    ->DisplayAggregatesOnly(true);

void BM_ModelStepOnlyDistributed(benchmark::State& state) {
  model_step_only(state, distributed_with_copies());
}
BENCHMARK(BM_ModelStepOnlyDistributed)
    ->Repetitions(15)
    ->ReportAggregatesOnly(true)
    ->DisplayAggregatesOnly(true);

// The per-tendon form at its largest: two families of 12 elements whose
// widths follow each tendon's tension, with tension and drive copies.
TsmModelSpec distributed_per_tendon() {
  TsmModelSpec s = distributed_spec();
  s.slip.tendon_widths = true;
  s.slip.elements = 12;
  s.slip.tension_copies = true;
  s.slip.drive_copies = true;
  for (std::size_t i = 0; i < 24; ++i)
    s.slip.weight[i] = 0.3;
  for (std::size_t i = 0; i < kMaxSlipBasis; ++i) {
    s.slip.tension_weight[i] = 0.01 * s.slip.weight[i];
    s.slip.drive_weight[i] = 0.005 * s.slip.weight[i];
  }
  return s;
}

void BM_ModelStepOnlyPerTendon(benchmark::State& state) {
  model_step_only(state, distributed_per_tendon());
}
BENCHMARK(BM_ModelStepOnlyPerTendon)
    ->Repetitions(15)
    ->ReportAggregatesOnly(true)
    ->DisplayAggregatesOnly(true);

// One differentiator's update per iteration over the encoder samples.
template <class Diff>
void run_differentiator(benchmark::State& state) {
  const Samples s = encoder_samples(1 << 16);
  Diff d;
  std::size_t i = 0;
  double t_offset = 0.0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(d.update(s.t[i] + t_offset, s.x[i]));
    if (++i == s.t.size()) i = 0, t_offset += 100.0;
  }
}

// The plain filter (the four Kalman channels and their sign), without the
// corrections (corrections.hpp), which BM_EstimatorStep includes.
void BM_DifferentiatorOnly(benchmark::State& state) {
  run_differentiator<Differentiator>(state);
}
BENCHMARK(BM_DifferentiatorOnly)
    ->Repetitions(15)
    ->ReportAggregatesOnly(true)
    ->DisplayAggregatesOnly(true);

// The differentiator the estimator runs: the filter with the rest and cruise
// corrections applied to its sign (corrections.hpp).
void BM_CorrectedDifferentiatorOnly(benchmark::State& state) {
  run_differentiator<CorrectedDifferentiator>(state);
}
BENCHMARK(BM_CorrectedDifferentiatorOnly)
    ->Repetitions(15)
    ->ReportAggregatesOnly(true)
    ->DisplayAggregatesOnly(true);

// The console table, and at the end the step's median over the sum of its
// parts' medians (real time), for each differentiator.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  using ConsoleReporter::ConsoleReporter;
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs)
      if (r.run_type == Run::RT_Aggregate && r.aggregate_name == "median")
        median_ns_[r.run_name.function_name] = r.GetAdjustedRealTime();
    ConsoleReporter::ReportRuns(runs);
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    const auto has = [&](const char* name) { return median_ns_.count(name) > 0; };
    if (!has("BM_EstimatorStep") || !has("BM_ModelStepOnly")) return;
    const double step = median_ns_["BM_EstimatorStep"], model = median_ns_["BM_ModelStepOnly"];
    for (const char* diff : {"BM_DifferentiatorOnly", "BM_CorrectedDifferentiatorOnly"}) {
      if (!has(diff)) continue;
      std::printf("step / (model + %s): %.2f (%.1f / (%.1f + %.1f) ns)\n", diff + 3,
                  step / (model + median_ns_[diff]), step, model, median_ns_[diff]);
    }
  }

 private:
  std::map<std::string, double> median_ns_;
};

}  // namespace

int main(int argc, char** argv) {
  // Another --benchmark_format: the library's own reporter, no ratios.
  bool console = true;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--benchmark_format=", 0) == 0 && arg != "--benchmark_format=console")
      console = false;
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  if (console) {
    // Colour as the library's default does it: only on a terminal.
    RatioReporter reporter(isatty(STDOUT_FILENO) ? benchmark::ConsoleReporter::OO_Color
                                                 : benchmark::ConsoleReporter::OO_None);
    benchmark::RunSpecifiedBenchmarks(&reporter);
  } else {
    benchmark::RunSpecifiedBenchmarks();
  }
  benchmark::Shutdown();
  return 0;
}
