// The whole identification of `tsm fit` on 40 s of 1 kHz data (the paper's
// model through realistic sensors): data preparation, the multi-start
// NLopt fit, validation scoring, uncertainty, plots and report.json, as the
// CLI does it. Target: <= 2 s wall on the project's 2-core machine, idle.
// Run: build/bin/bench_fit [repetitions]   (prints wall and CPU seconds;
// the CPU includes gnuplot's, which runs in child processes)
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "estimator/atomic_file.hpp"
#include "estimator/fit_workflow.hpp"
#include "estimator/plotting.hpp"
#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"
#include "realtime/quantile.hpp"

int main(int argc, char** argv) {
  using namespace tsmh::estimator;
  const int reps = argc > 1 ? std::max(1, std::atoi(argv[1])) : 3;
  const auto dir = std::filesystem::temp_directory_path() / "tsmh_bench_fit";
  std::filesystem::create_directories(dir);
  std::printf("bench_fit: tsm fit on 40 s at 1 kHz, %u hardware threads\n",
              std::thread::hardware_concurrency());
  std::vector<double> walls;
  // CPU seconds of this process and of its finished children (gnuplot).
  const auto cpu_now = [] {
    double s = 0.0;
    for (const int who : {RUSAGE_SELF, RUSAGE_CHILDREN}) {
      rusage u{};
      getrusage(who, &u);
      s += static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
           1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
    }
    return s;
  };
  for (int r = 0; r < reps; ++r) {
    SyntheticConfig c;
    c.seed = 1000 + static_cast<std::uint64_t>(r);
    const auto syn = make_synthetic(TsmFrictionModel(paper_spec()), c);
    const auto w0 = std::chrono::steady_clock::now();
    const double c0 = cpu_now();
    FitWorkflowOptions o;
    const FitRun run = run_fit(syn.recording, TsmFrictionModel(paper_spec()), "paper", o);
    const auto w1 = std::chrono::steady_clock::now();
    const auto plots =
        plot_friction(dir, "fit", run.data, {{"fitted", run.fit.simulated}}, "bench");
    const auto w2 = std::chrono::steady_clock::now();
    const double wall = std::chrono::duration<double>(w2 - w0).count();
    write_text_atomically(dir / "report.json",
                          fit_report_json(run, o, wall, plots.files, plots.error).dump(2));
    const double cpu = cpu_now() - c0;
    walls.push_back(wall);
    std::printf(
        "  run %d: wall %.2f s (identify %.2f s, rest of run_fit %.2f s, plots %.2f s), cpu "
        "%.2f s; %ld model runs, validation RMSE %.3f N, fit %.1f %%\n",
        r + 1, wall, run.fit.seconds,
        std::chrono::duration<double>(w1 - w0).count() - run.fit.seconds,
        std::chrono::duration<double>(w2 - w1).count(), cpu, run.fit.evaluations,
        run.validation.rmse, run.validation.fit_percent);
  }
  std::printf("bench_fit: wall median %.2f s, max %.2f s (target <= 2 s)\n",
              tsmh::realtime::median(walls), *std::max_element(walls.begin(), walls.end()));
  std::filesystem::remove_all(dir);
  return 0;
}
