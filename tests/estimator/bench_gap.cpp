// The whole model-gap workflow of `tsm gap` on 40 s of 1 kHz data: base fit,
// candidate rounds, re-identification, diagnostics, plots and report.json.
// Data: the paper's model with two hidden effects (load and position
// dependence; two rounds that accept, one that does not) and with none.
// Target: <= 10 s wall on the project's 2-core machine.
// Run: build/bin/bench_gap   (prints wall and CPU seconds)
#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <thread>

#include "estimator/atomic_file.hpp"
#include "estimator/model_gap.hpp"
#include "estimator/plotting.hpp"
#include "estimator/synthetic.hpp"

int main() {
  using namespace tsmh::estimator;
  const auto dir = std::filesystem::temp_directory_path() / "tsmh_bench_gap";
  std::filesystem::create_directories(dir);
  std::printf("bench_gap: tsm gap on 40 s at 1 kHz, %u hardware threads\n",
              std::thread::hardware_concurrency());
  struct Case {
    const char* name;
    bool hidden;
  };
  for (const Case c : {Case{"two hidden effects", true}, Case{"no hidden effect", false}}) {
    TsmModelSpec s = paper_spec();
    if (c.hidden) {
      s.add(TermKind::kLoadDependent).p = {0.03};
      s.add(TermKind::kPositionDependent).p = {0.25, 0.2};
    }
    SyntheticConfig sc;
    sc.seed = 2000;
    const auto rec = make_synthetic(TsmFrictionModel(s), sc).recording;
    const auto w0 = std::chrono::steady_clock::now();
    const std::clock_t c0 = std::clock();
    GapOptions o;
    const GapResult g = find_model_gaps(rec, TsmFrictionModel(paper_spec()), "paper", o);
    const auto plots = plot_friction(
        dir, "gap", g.data, {{"base", g.base_simulated}, {"final", g.final_simulated}}, "bench");
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - w0).count();
    write_text_atomically(dir / "report.json",
                          gap_report_json(g, o, plots.files, plots.error, wall).dump(2));
    write_text_atomically(dir / "summary.txt", gap_summary_text(g, o));
    const double cpu = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
    std::string found;
    for (const auto& e : g.effects)
      found += " " + e.name;
    std::printf(
        "  %s: wall %.1f s, cpu %.1f s, %zu rounds, %ld model runs, gap %.3f -> %.3f N, "
        "effects:%s\n",
        c.name, wall, cpu, g.rounds.size(), g.evaluations, g.gap_base.rmse, g.gap_final.rmse,
        found.empty() ? " none" : found.c_str());
  }
  std::printf("bench_gap: target <= 10 s wall per run\n");
  std::filesystem::remove_all(dir);
  return 0;
}
