#include "estimator/fit_workflow.hpp"

#include <cmath>
#include <cstdio>

#include "estimator/separable_fit.hpp"
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
  if (has("distributed_slip.load_weights"))
    return "contact at several known loads (a tip sensor or a calibrated load): free motion "
           "carries no distal load";
  if (has("distributed_slip.drive_weights"))
    return "tip loads of both signs (pressing on tissue, pulling on a grasp) with a tip sensor: "
           "which tendon carries the load is what they weigh";
  if (has("distributed_slip.tension_weights")) return "the same motion at several pretensions";
  if (has("distributed_slip")) return "reversals of many sizes, small (a few mrad) to large";
  if (has("load")) return "the same motion at several loads";
  if (has("position")) return "motion over the whole stroke";
  if (has("time")) return "a longer recording";
  return "motion that varies this term's variable more";
}

// Above this many times the noise floor a fit is "coarse", not "fair".
constexpr double kFairRatio = 3.0;
// The share of a force a hand tells apart (the just-noticeable difference
// of force is about 7-10 %): an error below it at a force is hard to feel.
constexpr double kForceJnd = 0.10;

}  // namespace

void explain_for_haptics(FitVerdict& v, double rmse_n, double radius_m, const MasterScale* master) {
  if (!(std::isfinite(rmse_n) && std::isfinite(radius_m) && radius_m > 0.0)) {
    v.meaning = "no pulley radius: the error cannot be given at the tip";
    return;
  }
  v.tip_rmse_nm = rmse_n * radius_m;
  v.meaning = "at the tool's tip the friction error is a distal-torque error of " +
              num(v.tip_rmse_nm) + " N m RMS (" + num(rmse_n) + " N x pulley radius " +
              num(radius_m) + " m)";
  if (master == nullptr || !std::isfinite(master->force_scale)) {
    v.meaning +=
        "; give tsm the server's config (--config) or --force-scale and --master-peak to "
        "have it on the master";
    return;
  }
  v.master_rmse_nm = std::fabs(master->force_scale) * v.tip_rmse_nm;
  v.meaning += "; on the master (force scale " + num(master->force_scale) + ", " + master->source +
               ") " + num(v.master_rmse_nm) + " N m RMS";
  if (std::isfinite(master->peak_nm) && master->peak_nm > 0.0) {
    v.master_fraction = v.master_rmse_nm / master->peak_nm;
    v.meaning += ", " + num(100.0 * v.master_fraction, 2) + " % of its peak torque " +
                 num(master->peak_nm) +
                 " N m: below the ~10 % of a force a hand can tell apart "
                 "for rendered torques above " +
                 num(v.master_rmse_nm / kForceJnd) + " N m (" +
                 num(100.0 * v.master_fraction / kForceJnd, 2) + " % of the peak)" +
                 (v.master_fraction / kForceJnd >= 1.0 ? ", so felt as a wrong force everywhere"
                                                       : ", felt as a wrong force on lighter ones");
  }
}

FitVerdict judge_fit(const ErrorMetrics& train, const ErrorMetrics& val, double noise,
                     const UncertaintyReport* u, const std::vector<RegimeError>* regimes,
                     double good_ratio) {
  FitVerdict v;
  const double ratio = noise > 0.0 ? val.rmse / noise : std::nan("");
  std::string text =
      "validation RMSE " + num(val.rmse) + " N against a noise floor of " + num(noise) +
      " N estimated from the measured friction's high-frequency part (ratio " + num(ratio) +
      ", good needs <= " + num(good_ratio) + ", fair <= " + num(kFairRatio) + "); train RMSE " +
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
      // A distributed-slip weight at 0 is the exact optimum of the
      // nonnegative least squares (an element the data does not need), not
      // a search stopped at its bound.
      if (p.name.rfind("distributed_slip.weights.", 0) == 0 && p.value == 0.0) continue;
      ++at_bound;
      problems.push_back(p.name + " " + at_bound_text(p) + ": " + bound_consequence(p) +
                         "; data that would help: " + data_that_helps(p.name));
    }
  }
  if (overfit)
    problems.push_back("validation RMSE " + num(val.rmse) + " N is over 1.5x the train RMSE " +
                       num(train.rmse) +
                       " N: over-fitted, or the friction changes over the recording");
  // Graded by how far the residual is above the measurement noise: good at
  // it, fair within 3x (small effects missing), coarse beyond (the model
  // misses structure the data show); poor when it explains under half of
  // the friction's variation.
  if (!(val.fit_percent >= 50.0)) {
    v.grade = "poor";
  } else if (!above_floor && at_bound == 0 && !overfit) {
    v.grade = "good";
  } else if (ratio <= kFairRatio) {
    v.grade = "fair";
  } else {
    v.grade = "coarse";
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
  const bool separable = has_linear_block(*run.fit.model) && o.fit.method != "nlopt";
  if (o.uncertainty) {
    // With distributed slip, the uncertainty of the searched values only:
    // the weights are the exact least-squares solution for them, and
    // neighbouring elements' weights are correlated by construction (their
    // sum is what the data determine), so per-weight errors say nothing.
    if (separable) {
      const auto& fitted = dynamic_cast<const TsmFrictionModel&>(*run.fit.model);
      TsmModelSpec held = fitted.spec();
      for (const auto& p : fitted.parameters())
        if (p.name.find("weights.") != std::string::npos) held.fixed.push_back(p.name);
      run.uncertainty = estimate_uncertainty(TsmFrictionModel(held), run.data);
    } else {
      run.uncertainty = estimate_uncertainty(*run.fit.model, run.data);
    }
    // The fit's weak prior holds what the data leave undetermined; say which.
    std::string held;
    for (const auto& p : run.uncertainty.parameters) {
      if (!p.fixed && !p.at_bound && !p.well_identified)
        held += (held.empty() ? "" : ", ") + p.name;
    }
    if (!held.empty() && o.fit.method == "lm" && !separable)
      run.notes.push_back("regularised: " + held +
                          " poorly determined by this data; the fit's weak prior kept them near "
                          "their start (their combination that the data do determine is fitted)");
  }
  run.verdict = judge_fit(run.train, run.validation, run.noise,
                          o.uncertainty ? &run.uncertainty : nullptr, &run.regimes);
  explain_for_haptics(run.verdict, run.validation.rmse, run.data.radius_m,
                      o.master ? &*o.master : nullptr);
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
    j["mean_error"] = r.mean_error;
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
  const auto num_or_null = [](double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  };
  r["quality"] = {{"verdict", run.verdict.grade},
                  {"reason", run.verdict.reason},
                  {"meaning", run.verdict.meaning},
                  {"tip_rmse_nm", num_or_null(run.verdict.tip_rmse_nm)},
                  {"master_rmse_nm", num_or_null(run.verdict.master_rmse_nm)},
                  {"master_fraction", num_or_null(run.verdict.master_fraction)}};
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
