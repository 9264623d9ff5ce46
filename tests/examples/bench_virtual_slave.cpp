// Offline speed of the virtual slave (both joints, sensors, controllers):
// how many simulated seconds per wall-clock second. Target: >= 20x.

#include <benchmark/benchmark.h>

#include "virtual_tissue_slave/offline.hpp"

namespace vts = tsmh::virtual_tissue_slave;

namespace {

// One 1 kHz control period: two joints x 10 physics substeps.
void BM_ControlTick(benchmark::State& state) {
  vts::SlaveParams p = vts::paper_slave();
  auto tissue = vts::tissue_preset("soft");
  tissue.surface_rad = 0.6;
  for (auto& j : p.joints)
    j.tissue = tissue;
  vts::VirtualSlave slave(p, 1);
  const auto scenario = vts::make_scenario("sine");
  double t = 0.0;
  for (auto _ : state) {
    const auto& s = slave.tick({scenario.reference(t, 0), scenario.reference(t, 1)});
    benchmark::DoNotOptimize(s.truth[0].tau_out);
    t += p.control_period_s;
  }
  // Simulated seconds per wall second = real-time factor.
  state.counters["x_realtime"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * p.control_period_s, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_ControlTick)->UseRealTime();

// A whole offline scenario run, as `virtual-slave --offline` does it (no CSV).
void BM_OfflineScenario(benchmark::State& state, const char* name) {
  vts::OfflineOptions o;
  o.scenario = vts::make_scenario(name);
  o.duration_s = 10.0;
  double simulated = 0.0;
  for (auto _ : state) {
    double sink = 0.0;
    const auto stats = vts::run_offline(
        vts::paper_slave(), o, [&](const vts::SlaveSample& s) { sink += s.truth[0].tau_out; });
    benchmark::DoNotOptimize(sink);
    simulated += stats.simulated_s;
  }
  state.counters["x_realtime"] = benchmark::Counter(simulated, benchmark::Counter::kIsRate);
}
BENCHMARK_CAPTURE(BM_OfflineScenario, sine, "sine")->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_OfflineScenario, palpate, "palpate")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_OfflineScenario, multisine, "multisine")
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
