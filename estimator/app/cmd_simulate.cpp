// tsm simulate --params (paper|FILE.yaml) IN.csv (or --input IN.csv) --output OUT.csv [--radius R]
// Runs a friction model over recorded (or synthetic) motion: OUT has t,F, and
// tau_out_est when the input has tau_in (or T1, T3) and a radius is known.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>

#include "commands.hpp"
#include "estimator/distal_estimator.hpp"
#include "estimator/estimator_settings.hpp"
#include "estimator/fit_metrics.hpp"
#include "estimator/model_io.hpp"
#include "estimator/simulate.hpp"
#include "output_checks.hpp"

namespace tsmh::tsm_cli {
namespace {

struct SimulateOptions {
  std::string params;
  std::string input;
  std::string output;
  std::optional<double> radius;
  estimator::DerivativeSource derivatives = estimator::DerivativeSource::kAutomatic;
  estimator::EstimatorSettings estimator;  ///< as haptic-server's joints: entries
};

// Without exact derivatives the friction is what haptic-server would have
// estimated: the same DistalTorqueEstimator (differentiator, sign decision,
// model), fed the same samples in the same order, never a smoother.
std::vector<double> causal_friction(const estimator::FrictionModel& model,
                                    const estimator::Recording& rec, const SimulateOptions& o) {
  const bool has_load = rec.has_tau_in() && std::isfinite(rec.radius_m);
  estimator::DistalTorqueEstimator est(model.clone(), has_load ? rec.radius_m : 1.0,
                                       o.estimator.differentiator(), o.estimator.start_state);
  const bool has_tensions = rec.T1.size() == rec.size() && rec.T3.size() == rec.size();
  std::vector<double> f(rec.size());
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const double tension = has_tensions ? 0.5 * (rec.T1[i] + rec.T3[i]) : std::nan("");
    f[i] =
        est.update(rec.t[i], rec.x_in[i], has_load ? rec.tau_in[i] : 0.0, tension, rec.x_out_at(i))
            .friction;
  }
  return f;
}

// The estimate against the recording's measured tau_out, beside the naive
// feedback (tau_in itself) as the reference: one number alone says nothing.
std::string simulate_comparison(const estimator::Recording& rec, const std::vector<double>& est) {
  const auto all = [&](std::size_t i) {
    return std::isfinite(rec.tau_out[i]) && std::isfinite(est[i]) && std::isfinite(rec.tau_in[i]);
  };
  const auto e = estimator::error_metrics(rec.tau_out, est, all);
  const auto naive = estimator::error_metrics(rec.tau_out, rec.tau_in, all);
  char b[512];
  std::snprintf(
      b, sizeof b,
      "tsm simulate: tau_out_est vs the recording's tau_out (%zu samples): RMSE %.4g N m, "
      "p2p %.4g N m, fit %.1f %%; the naive feedback (tau_in) vs tau_out: RMSE %.4g N m, "
      "p2p %.4g N m (estimate / naive RMSE %.2f)\n",
      e.samples, e.rmse, e.p2p, e.fit_percent, naive.rmse, naive.p2p,
      naive.rmse > 0.0 ? e.rmse / naive.rmse : std::nan(""));
  return b;
}

void run_simulate(const SimulateOptions& o, const Context& ctx) {
  check_outputs(
      {{"--output", o.output, OutputKind::kFile}},
      {{"the input", o.input}, model_input("--params", o.params), key_input(ctx.lcm_log)});
  auto model = estimator::load_model(o.params);
  const auto rec = ctx.sources.load(o.input, o.radius, {});
  const bool exact =
      o.derivatives == estimator::DerivativeSource::kExact ||
      (o.derivatives == estimator::DerivativeSource::kAutomatic && rec.has_derivatives());
  std::vector<double> f;
  if (exact) {
    const auto motion = estimator::motion_from_recording(rec, estimator::DerivativeSource::kExact);
    f = estimator::simulate_friction(*model, motion);
  } else {
    f = causal_friction(*model, rec, o);
  }
  estimator::Table out;
  out.source = o.output;
  out.set("t", rec.t);
  out.set("F", f);
  if (rec.has_tau_in() && std::isfinite(rec.radius_m)) {
    std::vector<double> est(rec.size());
    for (std::size_t i = 0; i < rec.size(); ++i)
      est[i] = rec.tau_in[i] - rec.radius_m * f[i];
    out.set("tau_out_est", std::move(est));
    out.meta["radius_m"] = std::to_string(rec.radius_m);
  }
  out.meta["model"] = model->kind() + " (" + o.params + ")";
  estimator::write_csv_table(out, o.output);
  std::cerr << "tsm simulate: " << rec.size() << " samples -> " << o.output << "\n";
  if (rec.has_tau_out()) {
    const auto* est = out.has("tau_out_est") ? &out.column("tau_out_est") : nullptr;
    if (est == nullptr) {
      std::cerr << "tsm simulate: the recording has tau_out but no tau_in (or no radius): no "
                   "distal estimate to compare with it\n";
    } else {
      std::cerr << simulate_comparison(rec, *est);
    }
  }
}

}  // namespace

void add_simulate_command(CLI::App& app, Context& ctx) {
  auto opts = std::make_shared<SimulateOptions>();
  auto* cmd = app.add_subcommand("simulate", "Run a friction model over recorded motion");
  cmd->add_option("--params", opts->params,
                  "Model: a preset (paper, dahl, ...) or a params YAML file")
      ->required();
  // The input by position or by --input: one required input, so neither is
  // marked REQUIRED on its own (the help listed both as required).
  auto* positional = cmd->add_option("input", opts->input,
                                     "Input CSV (t, x_in; optional tau_in or T1,T3; x_out; "
                                     "xd_in,xdd_in; tau_out to compare with); "
                                     "required, here or as --input");
  cmd->add_option("--input", opts->input, "The input CSV, as a flag (instead of the positional)")
      ->excludes(positional);
  cmd->add_option("--output", opts->output, "Output CSV (t, F[, tau_out_est])")->required();
  cmd->add_option("--radius", opts->radius,
                  "Pulley radius in m (overrides '# radius_m:' in the input)")
      ->check(CLI::PositiveNumber);
  const std::map<std::string, estimator::DerivativeSource> sources{
      {"auto", estimator::DerivativeSource::kAutomatic},
      {"differentiator", estimator::DerivativeSource::kDifferentiator},
      {"exact", estimator::DerivativeSource::kExact}};
  cmd->add_option("--derivatives", opts->derivatives,
                  "auto: xd_in/xdd_in when present, else the causal estimator haptic-server "
                  "runs (differentiator: always that; exact: xd_in/xdd_in)")
      ->transform(CLI::CheckedTransformer(sources, CLI::ignore_case));
  // The numeric estimator settings, named, ranged and explained as in
  // haptic-server's joints: entries (the YAML key in brackets).
  for (const auto& s : estimator::numeric_settings()) {
    cmd->add_option(std::string(s.flag), opts->estimator.*s.field,
                    std::string(s.help) + " (haptic-server's " + std::string(s.key) + ")")
        ->check(CLI::Validator(
            [&s](std::string& value) -> std::string {
              const std::string problem = s.problem(std::strtod(value.c_str(), nullptr));
              return problem.empty() ? "" : problem + ", got " + value;
            },
            ""));
  }
  std::map<std::string, estimator::StartState> starts;
  for (const char* name : {"free_tip", "zero"})
    starts[name] = *estimator::start_state_from_name(name);
  cmd->add_option("--start-state", opts->estimator.start_state,
                  "friction state at the first sample: free_tip (tared from tau_in, the "
                  "default) or zero")
      ->transform(CLI::CheckedTransformer(starts, CLI::ignore_case));
  cmd->callback([opts, &ctx] {
    if (opts->input.empty()) throw CLI::RequiredError("the input CSV (positional, or --input)");
    run_simulate(*opts, ctx);
  });
}

}  // namespace tsmh::tsm_cli
