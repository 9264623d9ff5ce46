#include "estimator/fit_workflow.hpp"

#include <cmath>
#include <cstdio>

#include "estimator/tsm_model.hpp"
#include "number_text.hpp"

namespace tsmh::estimator {
FitVerdict judge_fit(const ErrorMetrics& train, const ErrorMetrics& val, double noise) {
  FitVerdict v;
  const std::string numbers = "validation fit " + num(val.fit_percent) + " %, RMSE " +
                              num(val.rmse) + " N (train " + num(train.rmse) +
                              " N, measurement noise about " + num(noise) + " N)";
  const bool overfit = val.rmse > 1.5 * train.rmse;
  if (!(val.fit_percent >= 50.0)) {
    v.grade = "poor";
    v.reason = numbers + ": the model explains little of the measured friction";
  } else if (val.fit_percent >= 80.0 && !overfit) {
    v.grade = "good";
    v.reason =
        numbers + (val.rmse <= 1.5 * noise ? ": the residual is close to the measurement noise"
                                           : ": the model follows the measured friction closely");
  } else {
    v.grade = "fair";
    v.reason = numbers + (overfit ? ": much worse on validation than on train data (over-fit, or "
                                    "the friction changes over the record)"
                                  : ": parts of the friction are not explained (tsm gap finds "
                                    "where)");
  }
  return v;
}

FitRun run_fit(const Recording& rec, const FrictionModel& initial, const std::string& initial_name,
               const FitWorkflowOptions& o) {
  FitRun run;
  run.initial_name = initial_name;
  run.data = prepare_fit_data(rec, o.split, o.requirements, o.differentiator, o.derivatives,
                              o.offline);
  run.noise = noise_floor(run.data.measured);
  auto start = initial.clone();
  if (auto note = adapt_scale_to_data(*start, run.data); !note.empty()) run.notes.push_back(note);
  run.fit = identify(*start, run.data, o.fit);
  for (const auto& note : run.fit.notes)
    run.notes.push_back(note);
  run.train = error_metrics(run.data, run.fit.simulated, SampleRole::train);
  run.validation = error_metrics(run.data, run.fit.simulated, SampleRole::validation);
  run.regimes = regime_errors(run.data, run.fit.simulated, SampleRole::validation);
  if (o.uncertainty) run.uncertainty = estimate_uncertainty(*run.fit.model, run.data);
  run.verdict = judge_fit(run.train, run.validation, run.noise);
  return run;
}

nlohmann::json to_json(const ErrorMetrics& m) {
  return {{"rmse", m.rmse},
          {"p2p", m.p2p},
          {"fit_percent", m.fit_percent},
          {"bias", m.bias},
          {"samples", m.samples}};
}

nlohmann::json to_json(const std::vector<RegimeError>& regimes) {
  nlohmann::json a = nlohmann::json::array();
  for (const auto& r : regimes) {
    nlohmann::json j = to_json(r.metrics);
    j["name"] = r.name;
    j["group"] = r.group;
    j["where"] = r.where;
    j["concentration"] = r.concentration;
    j["magnitude_excess"] = r.magnitude_excess;
    a.push_back(std::move(j));
  }
  return a;
}

nlohmann::json to_json(const UncertaintyReport& u) {
  nlohmann::json params = nlohmann::json::array();
  for (const auto& p : u.parameters) {
    params.push_back({{"name", p.name},
                      {"value", p.value},
                      {"std_error", p.std_error},
                      {"lower", p.lower},
                      {"upper", p.upper},
                      {"unit", p.unit},
                      {"fixed", p.fixed},
                      {"at_bound", p.at_bound},
                      {"well_identified", p.well_identified}});
  }
  return {{"parameters", params},
          {"correlation", {{"names", u.free_names}, {"matrix", u.correlation}}},
          {"residual_std", u.residual_std},
          {"correlation_time_samples", u.correlation_time},
          {"condition_number", u.condition_number},
          {"warnings", u.warnings},
          {"notes", u.notes}};
}

nlohmann::json fit_report_json(const FitRun& run, const FitWorkflowOptions& o, double seconds,
                               const std::vector<std::string>& plots,
                               const std::string& plot_error) {
  const FitData& d = run.data;
  nlohmann::json starts = nlohmann::json::array();
  for (const auto& s : run.fit.starts) {
    starts.push_back({{"index", s.index},
                      {"global_rmse", s.global_rmse},
                      {"rmse", s.rmse},
                      {"evaluations", s.evaluations},
                      {"seconds", s.seconds},
                      {"stop", s.stop_reason}});
  }
  // How many starts ended within 2 % of the best: a measure of how reliably
  // the optimiser finds this optimum.
  int agreeing = 0;
  for (const auto& s : run.fit.starts)
    agreeing += s.rmse <= 1.02 * run.fit.starts[static_cast<std::size_t>(run.fit.best_start)].rmse;

  nlohmann::json model = {{"kind", run.fit.model->kind()}, {"initial", run.initial_name}};
  if (const auto* tsm = dynamic_cast<const TsmFrictionModel*>(run.fit.model.get())) {
    nlohmann::json terms = nlohmann::json::array();
    for (const auto& t : tsm->spec().terms)
      terms.push_back(std::string(term_info(t.kind).name));
    model["terms"] = terms;
  }
  nlohmann::json warnings = run.uncertainty.warnings;
  if (!plot_error.empty()) warnings.push_back("plots: " + plot_error);

  nlohmann::json r;
  r["tool"] = "tsm fit";
  r["data"] = {{"source", d.source},         {"samples", d.size()},
               {"duration_s", d.duration()}, {"radius_m", d.radius_m},
               {"reversals", d.reversals},   {"noise_floor", run.noise},
               {"derivatives", d.derivatives}};
  r["model"] = model;
  r["split"] = {{"rule", "alternate contiguous blocks, train first, after a warm-up"},
                {"block_s", d.block_s},
                {"warmup_s", o.split.warmup_s},
                {"train_samples", d.count(SampleRole::train)},
                {"validation_samples", d.count(SampleRole::validation)}};
  r["train"] = to_json(run.train);
  r["validation"] = to_json(run.validation);
  r["regimes"] = to_json(run.regimes);
  r["quality"] = {{"verdict", run.verdict.grade}, {"reason", run.verdict.reason}};
  const auto u = to_json(run.uncertainty);
  r["parameters"] = u["parameters"];
  r["correlation"] = u["correlation"];
  r["identifiability"] = {{"residual_std", u["residual_std"]},
                          {"correlation_time_samples", u["correlation_time_samples"]},
                          {"condition_number", u["condition_number"]},
                          {"notes", u["notes"]}};
  r["warnings"] = warnings;
  r["notes"] = run.notes;
  r["optimiser"] = {{"library", run.fit.library},
                    {"method", o.fit.method},
                    {"screened_starts", run.fit.screened},
                    {"global", run.fit.global_algorithm},
                    {"local", run.fit.local_algorithm},
                    {"seed", o.fit.seed},
                    {"starts", run.fit.starts.size()},
                    {"best_start", run.fit.best_start},
                    {"starts_within_2_percent", agreeing},
                    {"evaluations", run.fit.evaluations},
                    {"seconds", run.fit.seconds},
                    {"per_start", starts}};
  r["plots"] = plots;
  r["seconds"] = seconds;
  return r;
}

std::vector<std::string> fit_header_lines(const FitRun& run) {
  return {"identified by tsm fit from " + run.data.source + " (start: " + run.initial_name + ")",
          "validation: RMSE " + num(run.validation.rmse) + " N, p2p " + num(run.validation.p2p) +
              " N, fit " + num(run.validation.fit_percent) + " %; " + run.verdict.grade};
}

}  // namespace tsmh::estimator
