// What recalibration costs the loop: HapticLoop::tick with the
// recalibration idle and while it collects free motion (the only loop-side
// work: one sample copied per joint), and the identification that runs on
// the server's main thread (never in the loop) for 5 s of samples.
// A benchmark program (scripts/bench), not a ctest.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>

#include "estimator/tsm_model.hpp"
#include "fakes.hpp"
#include "haptics/haptic_loop.hpp"

namespace tsmh::haptics {
namespace {

struct Bench {
  explicit Bench(std::size_t capacity) {
    config.joints = 2;
    config.recalibration.collect_s = 1e6;  // keeps collecting for the whole run
    config.recalibration.capacity = capacity;
    for (int j = 0; j < 2; ++j)
      config.limits[j] = {0.8, 100.0};
    loop = std::make_unique<HapticLoop>(config, device, link, testing::paper_estimators());
  }
  void tick() {
    const double t = static_cast<double>(now) * 1e-9;
    link.push(now, 0.6 * std::sin(std::numbers::pi * t),
              25.0 + 5.0 * std::cos(std::numbers::pi * t), 20.0);
    loop->tick(now);
    now += 1'000'000;
  }
  LoopConfig config;
  testing::FakeDevice device;
  testing::FakeLink link;
  std::unique_ptr<HapticLoop> loop;
  std::int64_t now = 1'000'000'000;
};

void BM_TickIdle(benchmark::State& state) {
  Bench b(20'000);
  for (int i = 0; i < 3000; ++i)
    b.tick();  // past the start-up
  for (auto _ : state)
    b.tick();
  b.device.written.clear();
}

void BM_TickCollecting(benchmark::State& state) {
  Bench b(20'000);
  for (int i = 0; i < 3000; ++i)
    b.tick();
  b.loop->calibration().request(3);
  b.tick();
  if (b.loop->calibration().state() != CalibrationState::kCollecting)
    state.SkipWithError("not collecting");
  for (auto _ : state)
    b.tick();
}

void BM_IdentifyFiveSeconds(benchmark::State& state) {
  for (auto _ : state) {
    state.PauseTiming();
    Bench real(20'000);
    LoopConfig c = real.config;
    c.recalibration.collect_s = 5.0;
    real.loop =
        std::make_unique<HapticLoop>(c, real.device, real.link, testing::paper_estimators());
    for (int i = 0; i < 1000; ++i)
      real.tick();
    real.loop->calibration().request(3);
    for (int i = 0; i < 5100; ++i)
      real.tick();
    state.ResumeTiming();
    benchmark::DoNotOptimize(real.loop->calibration().identify_pending());
  }
}

BENCHMARK(BM_TickIdle)->Iterations(15'000)->Repetitions(5);
BENCHMARK(BM_TickCollecting)->Iterations(15'000)->Repetitions(5);
BENCHMARK(BM_IdentifyFiveSeconds)->Iterations(20)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace tsmh::haptics

BENCHMARK_MAIN();
