#include "estimator/fit_workflow.hpp"

#include <cmath>
#include <cstdio>

#include "estimator/tsm_model.hpp"
#include "number_text.hpp"

namespace tsmh::estimator {
namespace {

// What data would pin a parameter down (by the term it belongs to).
std::string data_that_helps(const std::string& name) {
  const auto has = [&](const char* part) { return name.find(part) != std::string::npos; };
  if (has("theta") || has("sigma"))
    return "reversals followed by long excursions (the hysteresis loop's sides)";
  if (has("lambda")) return "reversals at several accelerations, including slow creeping ones";
  if (has("rho")) return "steady sliding at constant speed in both directions";
  if (has("mu1") || has("kappa1")) return "sliding at several speeds, slow (< 0.2 rad/s) and fast";
  if (has("acceleration_dependence"))
    return "the same speeds reached while accelerating and while decelerating, at several "
           "accelerations";
  if (has("load")) return "the same motion at several loads";
  if (has("position")) return "motion over the whole stroke";
  if (has("time")) return "a longer recording";
  return "motion that varies this term's variable more";
}

}  // namespace

FitVerdict judge_fit(const ErrorMetrics& train, const ErrorMetrics& val, double noise,
                     const UncertaintyReport* u, const std::vector<RegimeError>* regimes,
                     double good_ratio) {
  FitVerdict v;
  const double ratio = noise > 0.0 ? val.rmse / noise : std::nan("");
  std::string text = "validation RMSE " + num(val.rmse) + " N against a noise floor of " +
                     num(noise) +
                     " N estimated from the measured friction's high-frequency part (ratio " +
                     num(ratio) + ", good needs <= " + num(good_ratio) + "); train RMSE " +
                     num(train.rmse) + " N, validation fit " + num(val.fit_percent) + " %";
  std::vector<std::string> problems;
  const bool overfit = val.rmse > 1.5 * train.rmse;
  const bool above_floor = !(ratio <= good_ratio);
  if (above_floor) {
    const double excess = std::sqrt(std::max(0.0, val.rmse * val.rmse - noise * noise));
    std::string where;
    if (regimes != nullptr) {
      const RegimeError* worst = nullptr;
      for (const auto& r : *regimes) {
        if (r.metrics.samples > 0 && (worst == nullptr || r.concentration > worst->concentration))
          worst = &r;
      }
      if (worst != nullptr)
        where = ", most in " + worst->name + " (" + worst->where + ": RMSE " +
                num(worst->metrics.rmse) + " N, " + num(worst->concentration) + "x its share)";
    }
    problems.push_back("the model leaves about " + num(excess) +
                       " N RMS beyond the noise unexplained" + where +
                       ": an effect the model lacks (run tsm gap to name it), or motion too "
                       "fast for the sample rate");
  }
  int at_bound = 0;
  if (u != nullptr) {
    for (const auto& p : u->parameters) {
      if (p.fixed || !p.at_bound) continue;
      ++at_bound;
      const bool low = std::fabs(p.value - p.lower) <= std::fabs(p.value - p.upper);
      problems.push_back(p.name + " = " + num(p.value) + " at its " + (low ? "lower" : "upper") +
                         " bound (" + num(low ? p.lower : p.upper) +
                         "): the data do not pin it down or want it beyond its range; data "
                         "that would help: " +
                         data_that_helps(p.name));
    }
  }
  if (overfit)
    problems.push_back("validation RMSE " + num(val.rmse) + " N is over 1.5x the train RMSE " +
                       num(train.rmse) +
                       " N: over-fitted, or the friction changes over the recording");
  if (!(val.fit_percent >= 50.0)) {
    v.grade = "poor";
  } else if (!above_floor && at_bound == 0 && !overfit) {
    v.grade = "good";
  } else {
    v.grade = "fair";
  }
  if (problems.empty()) {
    text += ": the residual is at the measurement noise";
  } else {
    text += ". Not good because: ";
    for (std::size_t i = 0; i < problems.size(); ++i)
      text += (i ? "; " : "") + problems[i];
  }
  v.reason = text;
  return v;
}

FitRun run_fit(const Recording& rec, const FrictionModel& initial, const std::string& initial_name,
               const FitWorkflowOptions& o) {
  FitRun run;
  run.initial_name = initial_name;
  run.data =
      prepare_fit_data(rec, o.split, o.requirements, o.differentiator, o.derivatives, o.offline);
  run.noise = noise_floor(run.data.measured);
  auto start = initial.clone();
  if (auto note = adapt_scale_to_data(*start, run.data); !note.empty()) run.notes.push_back(note);
  run.fit = identify(*start, run.data, o.fit);
  for (const auto& note : run.fit.notes)
    run.notes.push_back(note);
  run.train = error_metrics(run.data, run.fit.simulated, SampleRole::kTrain);
  run.validation = error_metrics(run.data, run.fit.simulated, SampleRole::kValidation);
  run.regimes = regime_errors(run.data, run.fit.simulated, SampleRole::kValidation);
  if (o.uncertainty) {
    run.uncertainty = estimate_uncertainty(*run.fit.model, run.data);
    // The fit's weak prior holds what the data leave undetermined; say which.
    std::string held;
    for (const auto& p : run.uncertainty.parameters) {
      if (!p.fixed && !p.at_bound && !p.well_identified)
        held += (held.empty() ? "" : ", ") + p.name;
    }
    if (!held.empty() && o.fit.method == "lm")
      run.notes.push_back("regularised: " + held +
                          " poorly determined by this data; the fit's weak prior kept them near "
                          "their start (their combination that the data do determine is fitted)");
  }
  run.verdict = judge_fit(run.train, run.validation, run.noise,
                          o.uncertainty ? &run.uncertainty : nullptr, &run.regimes);
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
  r["data"] = {{"source", d.source},          {"samples", d.size()},
               {"duration_s", d.duration()},  {"radius_m", d.radius_m},
               {"reversals", d.reversals},    {"noise_floor", run.noise},
               {"derivatives", d.derivatives}};
  r["model"] = model;
  r["split"] = {{"rule", "alternate contiguous blocks, train first, after a warm-up"},
                {"block_s", d.block_s},
                {"warmup_s", o.split.warmup_s},
                {"train_samples", d.count(SampleRole::kTrain)},
                {"validation_samples", d.count(SampleRole::kValidation)}};
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
  r["optimiser"] = {{"library", run.fit.library},          {"method", o.fit.method},
                    {"screened_starts", run.fit.screened}, {"global", run.fit.global_algorithm},
                    {"local", run.fit.local_algorithm},    {"seed", o.fit.seed},
                    {"starts", run.fit.starts.size()},     {"best_start", run.fit.best_start},
                    {"starts_within_2_percent", agreeing}, {"evaluations", run.fit.evaluations},
                    {"seconds", run.fit.seconds},          {"per_start", starts}};
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
