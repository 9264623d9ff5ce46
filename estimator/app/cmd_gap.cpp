// tsm gap DATA [--radius R] --output DIR [--base paper|dahl|FILE] [--seed N] [--margin F]
//              [--max-effects N] [--candidates a,b,...] [--threads N]
// The model-gap workflow (docs/model-gap.md): fit the base model,
// find where it disagrees with the measurement, name the missing effects and
// show the gap shrink. DIR gets report.json (docs/data-formats.md), summary.txt,
// params.yaml (the final model) and plots; on any error nothing is written.

#include <chrono>
#include <cmath>
#include <iostream>

#include "commands.hpp"
#include "estimator/atomic_file.hpp"
#include "estimator/fit_workflow.hpp"
#include "estimator/model_gap.hpp"
#include "estimator/model_io.hpp"
#include "estimator/plotting.hpp"
#include "estimator/staged_output.hpp"
#include "fit_input_options.hpp"
#include "output_checks.hpp"
#include "progress_line.hpp"

namespace tsmh::tsm_cli {
namespace {

struct GapCliOptions {
  FitInputCliOptions in;
  std::string output;
  std::string base = "paper";
  double margin = 0.10;
  int max_effects = 4;
  std::vector<std::string> candidates;
};

void run_gap_command(const GapCliOptions& o, const Context& ctx) {
  const auto t0 = std::chrono::steady_clock::now();
  check_outputs({{"--output", o.output, OutputKind::kFolder}},
                {{"the data", o.in.data}, model_input("--base", o.base), key_input(ctx.lcm_log)});
  const auto loaded = load_fit_recording(ctx, o.in.data, o.in.radius, o.in.free_motion);
  const auto& rec = loaded.recording;
  const auto base = estimator::load_model(o.base);
  const auto master = master_scale(o.in.master);
  estimator::StagedDirectory dir(o.output);  // fails early on an unusable path

  estimator::GapOptions go;
  go.base_fit.seed = o.in.seed;
  go.base_fit.threads = o.in.threads;
  go.threads = o.in.threads;
  go.margin = o.margin;
  go.max_effects = o.max_effects;
  go.candidates = o.candidates;
  go.derivatives = estimator::derivatives_from_name(o.in.derivatives);
  ProgressLine line("tsm gap");
  go.progress = [&](const std::string& s) { line.update(s); };
  const estimator::GapResult g = estimator::find_model_gaps(rec, *base, o.base, go);
  line.finish();

  std::vector<std::string> plots;
  std::string plot_error;
  const auto curves = estimator::plot_friction(
      dir.staging(), "gap", g.data,
      {{"base (" + o.base + ")", g.base_simulated}, {"with the effects found", g.final_simulated}},
      "tsm gap");
  plots = curves.files;
  plot_error = curves.error;
  if (plot_error.empty()) {
    estimator::RegimeBars bars;
    bars.series = {"base", "final"};
    bars.rmse.resize(2);
    for (std::size_t i = 0; i < g.regimes_base.size(); ++i) {
      bars.regimes.push_back(g.regimes_base[i].name);
      bars.rmse[0].push_back(g.regimes_base[i].metrics.rmse);
      bars.rmse[1].push_back(g.regimes_final[i].metrics.rmse);
    }
    const auto r = estimator::plot_regimes(dir.staging(), "gap", bars,
                                           "tsm gap: validation RMSE per regime, before and after");
    plot_error = r.error;
    plots.insert(plots.end(), r.files.begin(), r.files.end());
  }
  // The shape of each effect found: the friction it adds against its variable.
  // A shape flat at zero (an effect that acts through the friction's memory,
  // not as a function of one variable) is not drawn: a flat line at zero
  // reads as "this effect does nothing"; the summary says why it is absent.
  std::vector<std::string> not_plotted;
  for (std::size_t k = 0; k < g.effects.size() && plot_error.empty(); ++k) {
    const auto& e = g.effects[k];
    if (e.shape.empty()) continue;  // a structure's copies: their sizes are its parameters
    if (estimator::shape_is_flat(e.shape)) {
      not_plotted.push_back(e.name +
                            ": no shape plot, the friction it adds is zero at every one "
                            "of the " +
                            std::to_string(e.shape.size()) + " points against " + e.variable +
                            " (it acts through the friction's state, e.g. its memory of past "
                            "motion, not as a function of " +
                            e.variable + ")");
      continue;
    }
    const std::string unit = e.variable == "x"               ? "x (rad)"
                             : e.variable == "load"          ? "load |tau_in|/R (N)"
                             : e.variable == "distal_load"   ? "distal load tau_out/R (N)"
                             : e.variable == "tension"       ? "tension (N)"
                             : e.variable == "element_width" ? "element width (rad)"
                             : e.variable == "t"             ? "t (s)"
                                                             : "|xd| (rad/s)";
    const auto r = estimator::plot_xy(
        dir.staging(), "gap_effect" + std::to_string(k + 1) + "_" + e.name, e.shape, unit,
        "added friction (N)", e.name + " (" + e.form + "): friction added vs " + unit);
    plot_error = r.error;
    plots.insert(plots.end(), r.files.begin(), r.files.end());
  }
  if (!plot_error.empty()) std::cerr << "tsm gap: warning: plots: " << plot_error << "\n";

  std::vector<std::string> header = {"final model of tsm gap on " + g.data.source + " (base " +
                                     o.base + ")"};
  std::string found;
  for (const auto& e : g.effects)
    found += (found.empty() ? "" : ", ") + e.name;
  header.push_back("effects added: " + (found.empty() ? std::string("none") : found));
  estimator::write_text_atomically(dir.file("params.yaml"),
                                   estimator::model_to_yaml(*g.final_model, header));
  // What the gap left means in the hand (the verdict layer of tsm fit).
  estimator::FitVerdict meaning;
  estimator::explain_for_haptics(meaning, g.gap_final.rmse, g.data.radius_m,
                                 master ? &*master : nullptr);
  std::string summary =
      estimator::gap_summary_text(g, go) + "For haptics, the gap after: " + meaning.meaning + ".\n";
  for (const auto& n : not_plotted)
    summary += "Plots: " + n + ".\n";
  estimator::write_text_atomically(dir.file("summary.txt"), summary);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto report = estimator::gap_report_json(g, go, plots, plot_error, seconds);
  if (loaded.free_motion) report["free_motion"] = free_motion_json(*loaded.free_motion);
  const auto num_or_null = [](double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  };
  report["plots_not_written"] = not_plotted;
  report["haptics"] = {{"meaning", meaning.meaning},
                       {"tip_rmse_nm", num_or_null(meaning.tip_rmse_nm)},
                       {"master_rmse_nm", num_or_null(meaning.master_rmse_nm)},
                       {"master_fraction", num_or_null(meaning.master_fraction)}};
  estimator::write_text_atomically(dir.file("report.json"), report.dump(2) + "\n");
  dir.commit();

  for (const auto& n : loaded.notes)
    std::cerr << "tsm gap: note: " << n << "\n";
  std::cerr << summary << "tsm gap: " << seconds << " s; report, summary, params.yaml and plots in "
            << o.output << "\n";
}

}  // namespace

void add_gap_command(CLI::App& app, Context& ctx) {
  auto opts = std::make_shared<GapCliOptions>();
  auto* cmd = app.add_subcommand(
      "gap",
      "Find where the model and the measurement disagree and name the missing effect "
      "(docs/model-gap.md)");
  add_recording_options(*cmd, opts->in);
  cmd->add_option("--output", opts->output,
                  "Directory for report.json, summary.txt, params.yaml and plots")
      ->required();
  cmd->add_option("--base", opts->base,
                  "Base model: a tsm preset (paper, dahl) or a tsm params file (default paper)");
  cmd->add_option("--margin", opts->margin,
                  "Validation-RMSE reduction an effect must bring to be accepted (default 0.10)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--max-effects", opts->max_effects, "Most effects to add (default 4)")
      ->check(CLI::Range(0, 16));
  cmd->add_option("--candidates", opts->candidates,
                  "Candidate effects to try (default: all but coulomb and the |tau_in|/R load "
                  "forms): viscous, load_dependent, position_dependent, time_varying, "
                  "tension_dependent, hysteresis_elements, direction_asymmetry, stribeck, "
                  "acceleration_dependence, reversal_offset, and the structural "
                  "distributed_slip (with its tension copies, or its per-tendon families when "
                  "T1 and T3 are recorded, when tension_dependent is named too), load_copies, "
                  "tension_copies, tendon_widths, distal_slip (slip driven from the tip, when "
                  "x_out is recorded); a family brings all its forms")
      ->delimiter(',');
  add_fit_input_options(*cmd, opts->in, ctx);
  cmd->callback([opts, &ctx] { run_gap_command(*opts, ctx); });
}

}  // namespace tsmh::tsm_cli
