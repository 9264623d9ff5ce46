#pragma once
// The model-gap workflow (`tsm gap`): find where the simulated and
// the measured friction disagree, name the missing effect, add it to the
// model and show the gap shrink.
//
//  1. Fit the base model (a full identification) and measure the gap on
//     validation data; localise it (per-regime errors) and diagnose the
//     residual (whiteness; how much of it each candidate term's regressor
//     explains, to first order).
//  2. For every candidate form of the catalog (sliding_terms.hpp) whose
//     effect (family) is not yet in the model: scan its shape parameters
//     (step time, ripple wavenumber, bump place and width, saturation load)
//     by first-order projection, add it at the best shape, refit locally
//     (Levenberg-Marquardt from the current optimum, the new term seeded by
//     the first-order estimate), measure the validation gap, its
//     significance and BIC.
//  3. Accept the candidate that shrinks the validation RMSE most when it
//     shrinks it by at least `margin` (10 %), or significantly and by at
//     least half of the MSE above the noise floor; polish the augmented
//     model; repeat until nothing qualifies or the gap reaches the
//     measurement-noise floor. Effects are named by family.
//  4. Confounds: a rival effect that explained most of the same residual is
//     reported with the named one and the experiment that separates them.
// docs/model-gap.md explains the margin, the floor and the evidence.

#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "estimator/fit_data.hpp"
#include "estimator/fit_metrics.hpp"
#include "estimator/identification.hpp"
#include "estimator/recording.hpp"
#include "estimator/sliding_terms.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {

struct GapOptions {
  FitOptions base_fit;  ///< the base model's global fit
  /// Candidate term or effect names; empty: every catalog term except
  /// coulomb, and the structural ones: distributed_slip (elasto-slide
  /// elements), then on a model with it load_copies and tension_copies.
  std::vector<std::string> candidates;
  /// A candidate must shrink the validation RMSE by at least this fraction.
  double margin = 0.10;
  /// Stop when the validation RMSE is within this factor of the noise floor.
  double noise_stop = 1.03;
  /// A candidate with a smaller gain still qualifies when its improvement is
  /// significant (z-score of the per-sample drop in squared validation error,
  /// over its correlation time, >= min_z) and it explains at least
  /// min_excess_share of the validation MSE above the noise floor: with the
  /// base at the floor a real effect can be small against the noise.
  double min_z = 1.5;
  double min_excess_share = 0.5;
  /// Candidates whose regressors explain less than this share of the
  /// residual (first order) are not refitted.
  double min_explained = 0.0;
  int max_effects = 4;
  /// Budget of each candidate's local refit (per start): BOBYQA on the
  /// decimated data, then on the full-rate data.
  int refit_coarse_evaluations = 300;
  int refit_evaluations = 100;
  /// lm: Levenberg-Marquardt iterations of each candidate's full-rate polish.
  int refit_polish_iterations = 3;
  /// A rival effect that shrank the gap by at least the margin and by at
  /// least this fraction of the named effect's shrink, and added nothing
  /// once that was in, is reported as confounded with it.
  double confound_ratio = 0.5;
  /// ... unless the named effect still qualifies on top of the rival and
  /// keeps at least this fraction of its own gain there.
  double confound_extra = 0.5;
  /// After accepting an effect, fit the augmented model to convergence
  /// (warm, from the candidate's refit, time parameters held within 10 ms of
  /// the refit's value), kept when it fits the train data better.
  bool reidentify = true;
  /// Worker threads for the candidates (each refit runs on one); 0: all cores.
  int threads = 0;
  SplitConfig split;
  DataRequirements requirements;
  DifferentiatorConfig differentiator;
  /// Where xd, xdd come from (default: exact columns, else offline smoothing).
  FitDerivatives derivatives = FitDerivatives::kAutomatic;
  OfflineDerivativeConfig offline;
  /// Progress text, called from the calling thread.
  std::function<void(const std::string&)> progress;
};

/// Whiteness of a residual and which candidate explains it.
struct ResidualDiagnostics {
  double lag1_autocorrelation = 0.0;
  double correlation_time = 1.0;  ///< samples (1 for white noise)
  double ljung_box = 0.0;         ///< Q over lags 1..20 (white: about 20)
  bool white = false;             ///< correlation time < 2 samples
  struct Regressor {
    std::string name;        ///< candidate term
    double explained = 0.0;  ///< fraction of the residual's energy its regressors explain (train)
  };
  std::vector<Regressor> regressors;  ///< best first
};

struct CandidateTrial {
  std::string name;         ///< the term (form) tried
  std::string family;       ///< the effect it is a form of (term_family)
  double explained = 0.0;   ///< first-order: fraction of the residual its regressors explain
  ErrorMetrics validation;  ///< after the refit
  double train_mse = 0.0;
  double bic = 0.0;           ///< effective-sample BIC on train data (lower is better)
  double delta_bic = 0.0;     ///< vs the current model
  double gain = 0.0;          ///< relative validation RMSE reduction (0.3 = 30 % smaller)
  double z = 0.0;             ///< significance of the reduction (see GapOptions::min_z)
  double excess_share = 0.0;  ///< share of the MSE above the noise floor it removed
  bool skipped = false;       ///< not refitted: its first-order share was below min_explained
  /// Distributed slip tried instead of the base's Bouc-Wen hysteresis (its
  /// elements and sliding functions alone) and kept: it fitted better.
  bool replaces_hysteresis = false;
  std::size_t free_parameters = 0;
  bool qualifies = false;
  bool accepted = false;
  std::vector<double> values;  ///< fitted parameter values (parameters() order)
  TsmModelSpec fitted;         ///< the refitted model (the current one with the effect)
  long evaluations = 0;
};

/// A rival of the accepted candidate (another family that shrank the gap
/// nearly as much): the accepted one refitted on top of the rival.
struct RivalCheck {
  std::string family;
  double gain = 0.0;               ///< the rival's own gain in the round
  double winner_gain_after = 0.0;  ///< the accepted effect's gain once the rival is in
  bool winner_still_qualifies = false;
};

struct GapRound {
  ErrorMetrics before;
  std::vector<RivalCheck> rivals;
  std::vector<CandidateTrial> trials;  ///< best gain first
  int accepted = -1;                   ///< index into trials, -1: none
  std::string stop_reason;             ///< when the workflow stopped after this round
};

struct EffectFound {
  std::string name;      ///< the effect (term family): viscous, load_dependent, ...
  std::string form;      ///< the term that expressed it (e.g. position_ripple)
  std::string variable;  ///< what the added term depends on: x, load, t or speed
  /// The added friction (N, gamma x the term's level) against `variable`,
  /// sorted by the variable, thinned to a few hundred points.
  std::vector<std::pair<double, double>> shape;
  /// Other effects that explained the same residual (see Confound).
  std::vector<std::string> confounded_with;
  std::string meaning;  ///< the catalog's physical meaning
  std::string where;    ///< where its absence shows, and where the residual fell most
  ErrorMetrics gap_after;
  double gain = 0.0;
  std::vector<std::pair<std::string, double>> parameters;  ///< the term's fitted values
};

/// Two effects that explained the same residual: both shrank the gap by at
/// least the margin when tried, the workflow named one, and the other added
/// nothing after it. The data cannot tell them apart.
struct Confound {
  std::string named;  ///< the effect the workflow kept
  std::string rival;  ///< the other one
  double named_gain = 0.0;
  double rival_gain = 0.0;  ///< when tried in the same round
  std::string warning;      ///< for people, with the separating experiment
  std::string experiment;   ///< the experiment that separates them
};

struct GapResult {
  std::string base_name;
  FitData data;
  double noise = 0.0;  ///< measurement-noise floor of F, N (fit_metrics.hpp)

  std::unique_ptr<FrictionModel> base_model;
  std::vector<double> base_simulated;
  ErrorMetrics gap_base;
  std::vector<RegimeError> regimes_base;
  ResidualDiagnostics diagnostics_base;

  std::vector<GapRound> rounds;
  std::vector<EffectFound> effects;
  std::vector<Confound> confounds;

  std::unique_ptr<FrictionModel> final_model;
  std::vector<double> final_simulated;
  ErrorMetrics gap_final;
  std::vector<RegimeError> regimes_final;
  ResidualDiagnostics diagnostics_final;
  std::string stop_reason;
  long evaluations = 0;
  double seconds = 0.0;
};

/// Runs the workflow. `base` must be a TsmFrictionModel (the composable
/// model); throws std::invalid_argument otherwise, DataError for bad data.
GapResult find_model_gaps(const Recording& rec, const FrictionModel& base,
                          const std::string& base_name, const GapOptions& options = {});
/// The same on data already prepared (prepare_fit_data).
GapResult find_model_gaps(FitData data, const FrictionModel& base, const std::string& base_name,
                          const GapOptions& options = {});

/// Residual diagnostics of `simulated` against the data (validation samples
/// for whiteness, train samples for the regressors of `candidates`).
ResidualDiagnostics diagnose_residual(const FitData& data, const TsmFrictionModel& model,
                                      std::span<const double> simulated,
                                      const std::vector<TermKind>& candidates);

/// report.json of docs/data-formats.md (base, gap_base, effects[{name, where,
/// gap_after}], gap_final) with the evidence around it.
nlohmann::json gap_report_json(const GapResult& result, const GapOptions& options,
                               const std::vector<std::string>& plots, const std::string& plot_error,
                               double seconds);

/// The human-readable summary: what disagreed, where, which effect it names
/// and why, the gap before and after.
std::string gap_summary_text(const GapResult& result, const GapOptions& options);

/// True when an effect's shape adds no friction anywhere (every point within
/// 1e-12 N of zero): its plot would be a flat line at zero, so none is drawn.
bool shape_is_flat(const std::vector<std::pair<double, double>>& shape);

}  // namespace tsmh::estimator
