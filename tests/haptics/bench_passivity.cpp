// Cost per tick of the issue-21 stages for two joints, what they add to the
// loop's compute time: the oscillation detector's update, and the passivity
// controller's control + commit (+ a slave sample every tick, the worst case).
#include <benchmark/benchmark.h>

#include <cmath>

#include "haptics/oscillation_detector.hpp"
#include "haptics/passivity.hpp"

namespace {

using namespace tsmh::haptics;

void BM_OscillationDetector2Joints(benchmark::State& state) {
  OscillationDetector d(2, {}, 1000.0);
  JointArray tau{};
  double t = 0;
  for (auto _ : state) {
    t += 1e-3;
    tau[0] = 0.2 + 0.01 * std::sin(20 * t);
    tau[1] = 0.1;
    benchmark::DoNotOptimize(d.update(tau, 1e-3));
  }
}
BENCHMARK(BM_OscillationDetector2Joints);

void BM_Passivity2Joints(benchmark::State& state) {
  PassivityConfig c;
  c.enabled = state.range(0) != 0;
  PassivityChannel p[2] = {PassivityChannel(c), PassivityChannel(c)};
  double t = 0;
  for (auto _ : state) {
    t += 1e-3;
    for (auto& ch : p) {
      ch.slave_sample(-0.2 * std::cos(7 * t), 0.1 * std::sin(7 * t - 0.3));
      const double out = ch.control(0.1 * std::sin(7 * t), -0.2 * std::cos(7 * t), 1e-3);
      ch.commit(out);
      benchmark::DoNotOptimize(out);
    }
  }
}
BENCHMARK(BM_Passivity2Joints)->Arg(0)->Arg(1);

}  // namespace

BENCHMARK_MAIN();
