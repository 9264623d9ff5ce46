// tsm fit DATA [--radius R] --output PARAMS.yaml [--report DIR] [--model paper|dahl|FILE]
//              [--seed N] [--starts N] [--threads N] [--block S]
// Identifies the friction model's parameters from recorded data
// (docs/identification.md). Writes the params file and, with --report, a
// directory with report.json and plots; on any error it writes nothing.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

#include "commands.hpp"
#include "estimator/atomic_file.hpp"
#include "estimator/fit_workflow.hpp"
#include "estimator/model_io.hpp"
#include "estimator/plotting.hpp"
#include "estimator/staged_output.hpp"
#include "fit_input_options.hpp"
#include "output_checks.hpp"
#include "progress_line.hpp"

namespace tsmh::tsm_cli {
namespace {

struct FitCliOptions {
  FitInputCliOptions in;
  std::string output;
  std::string report;
  std::string model = "paper";
  int starts = 4;
  double block_s = 2.0;
  std::string method = "lm";
};

std::string progress_text(const estimator::FitProgress& p) {
  char best[32] = "-";
  if (std::isfinite(p.best_rmse)) std::snprintf(best, sizeof best, "%.4g N", p.best_rmse);
  char buf[160];
  std::snprintf(buf, sizeof buf,
                "%s stage, starts done %d/%d, %ld model runs, best RMSE %s, %.1f s", p.stage,
                p.starts_done, p.starts_total, p.evaluations, best, p.elapsed_s);
  return buf;
}

void run_fit_command(const FitCliOptions& o, const Context& ctx) {
  const auto t0 = std::chrono::steady_clock::now();
  check_outputs(
      {{"--output", o.output, OutputKind::kFile}, {"--report", o.report, OutputKind::kFolder}},
      {{"the data", o.in.data}, model_input("--model", o.model), key_input(ctx.lcm_log)});
  const auto loaded = load_fit_recording(ctx, o.in.data, o.in.radius, o.in.free_motion);
  const auto& rec = loaded.recording;
  const auto initial = estimator::load_model(o.model);
  const auto master = master_scale(o.in.master);

  estimator::FitWorkflowOptions wo;
  wo.fit.seed = o.in.seed;
  wo.fit.starts = o.starts;
  wo.fit.threads = o.in.threads;
  wo.split.block_s = o.block_s;
  wo.fit.method = o.method;
  wo.derivatives = estimator::derivatives_from_name(o.in.derivatives);
  wo.master = master;
  ProgressLine line("tsm fit");
  wo.fit.progress = [&](const estimator::FitProgress& p) { line.update(progress_text(p)); };
  estimator::FitRun run = estimator::run_fit(rec, *initial, o.model, wo);
  line.finish();
  run.notes.insert(run.notes.end(), loaded.notes.begin(), loaded.notes.end());

  std::optional<estimator::StagedDirectory> dir;
  if (!o.report.empty()) {
    dir.emplace(o.report);
    const auto plots = estimator::plot_friction(
        dir->staging(), "fit", run.data, {{"fitted " + run.fit.model->kind(), run.fit.simulated}},
        "tsm fit");
    if (!plots.error.empty()) std::cerr << "tsm fit: warning: no plots: " << plots.error << "\n";
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    auto report = estimator::fit_report_json(run, wo, seconds, plots.files, plots.error);
    if (loaded.free_motion) report["free_motion"] = free_motion_json(*loaded.free_motion);
    estimator::write_text_atomically(dir->file("report.json"), report.dump(2) + "\n");
    dir->commit();
  }
  try {
    estimator::save_model(*run.fit.model, o.output, estimator::fit_header_lines(run));
  } catch (...) {
    if (dir) dir->roll_back();
    throw;
  }

  // One line per problem; report.json keeps every warning.
  for (const auto& w : estimator::grouped_warnings(run.uncertainty))
    std::cerr << "tsm fit: warning: " << w << "\n";
  for (const auto& n : run.notes)
    std::cerr << "tsm fit: note: " << n << "\n";
  std::cerr << "tsm fit: verdict " << run.verdict.grade << ": " << run.verdict.reason << "\n";
  std::cerr << "tsm fit: for haptics: " << run.verdict.meaning << "\n";
  std::fprintf(stderr,
               "tsm fit: validation RMSE %.4g N, p2p %.4g N, fit %.1f %% (%s); %ld model runs in "
               "%.1f s -> %s%s%s\n",
               run.validation.rmse, run.validation.p2p, run.validation.fit_percent,
               run.verdict.grade.c_str(), run.fit.evaluations, run.fit.seconds, o.output.c_str(),
               o.report.empty() ? "" : ", report in ", o.report.c_str());
}

}  // namespace

void add_fit_command(CLI::App& app, Context& ctx) {
  auto opts = std::make_shared<FitCliOptions>();
  auto* cmd = app.add_subcommand(
      "fit",
      "Identify the friction model's parameters from recorded data (docs/identification.md)");
  add_recording_options(*cmd, opts->in);
  cmd->add_option("--output", opts->output, "Params file to write (YAML, read by simulate/gap)")
      ->required();
  cmd->add_option("--report", opts->report, "Directory for report.json and plots");
  cmd->add_option("--model", opts->model,
                  "Model to fit and its starting values: a preset (paper, dahl, ...) or a params "
                  "file (default paper)");
  cmd->add_option(
         "--starts", opts->starts,
         "Starts: lm, the screened candidates polished on full-rate data; nlopt, independent "
         "starts (default 4)")
      ->check(CLI::Range(1, 64));
  cmd->add_option("--block", opts->block_s,
                  "Length of the alternating train/validation blocks, s (default 2)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--method", opts->method,
                  "Optimiser: lm (informed multi-start + Levenberg-Marquardt, default; for a "
                  "model with distributed_slip: separable), separable (the weights solved "
                  "exactly, the elements' spread searched) or nlopt (MLSL + BOBYQA)")
      ->check(CLI::IsMember({"lm", "separable", "nlopt"}));
  add_fit_input_options(*cmd, opts->in, ctx);
  cmd->callback([opts, &ctx] { run_fit_command(*opts, ctx); });
}

}  // namespace tsmh::tsm_cli
