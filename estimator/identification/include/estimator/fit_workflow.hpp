#pragma once
// `tsm fit` as a library call: prepare the data, identify, score on
// validation (overall and per regime), estimate the parameters' uncertainty,
// judge the fit, and build report.json (docs/data-formats.md). The CLI adds only
// file handling, so tests exercise exactly what users run.

#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "estimator/fit_data.hpp"
#include "estimator/fit_metrics.hpp"
#include "estimator/identification.hpp"
#include "estimator/uncertainty.hpp"

namespace tsmh::estimator {

struct FitVerdict {
  std::string grade;    ///< "good", "fair", "coarse" or "poor"
  std::string reason;   ///< one sentence with the numbers
  std::string meaning;  ///< the error at the tool's tip and, when known, on the master
  double tip_rmse_nm = std::nan("");      ///< validation RMSE x pulley radius, N m
  double master_rmse_nm = std::nan("");   ///< x force scale: on the master, N m
  double master_fraction = std::nan("");  ///< master_rmse_nm / the master's peak torque
};

/// The master that renders the estimate, to say what an error means in the
/// hand: from the server's config (tsm fit --config) or --force-scale and
/// --master-peak.
struct MasterScale {
  double force_scale = std::nan("");  ///< master N m per slave N m
  double peak_nm = std::nan("");      ///< the master joint's peak torque, N m
  std::string source;                 ///< where they came from, for the text
};

/// What a friction RMSE (N) means for haptics: x pulley radius at the tip
/// in N m and, given the master, on the master in N m and as a share of its
/// peak, with the force below which that error exceeds the ~10 % of a force
/// a hand can tell apart. Fills the verdict's meaning and figures.
void explain_for_haptics(FitVerdict& v, double rmse_n, double radius_m, const MasterScale* master);

/// good: validation RMSE within `good_ratio` (1.2) x the noise floor
/// estimated from the data (`noise`), no free parameter at a bound, and no
/// sign of over-fitting (validation RMSE within 1.5x train). poor: validation
/// fit < 50 %. fair: within 3x the floor; coarse: beyond (the model misses
/// structure the data show). The reason gives the raw
/// figures beside the ratio, says what is wrong and what data would help.
/// `uncertainty` (optional) supplies the parameters at a bound, `regimes`
/// (optional) where the residual concentrates.
FitVerdict judge_fit(const ErrorMetrics& train, const ErrorMetrics& validation, double noise,
                     const UncertaintyReport* uncertainty = nullptr,
                     const std::vector<RegimeError>* regimes = nullptr, double good_ratio = 1.2);

struct FitRun {
  FitData data;
  FitResult fit;
  ErrorMetrics train;
  ErrorMetrics validation;
  std::vector<RegimeError> regimes;  ///< on validation samples
  UncertaintyReport uncertainty;
  double noise = 0.0;  ///< noise_floor of the measured friction, N
  FitVerdict verdict;
  std::vector<std::string> notes;  ///< e.g. a gamma rescale
  std::string initial_name;        ///< the preset or file the fit started from
};

struct FitWorkflowOptions {
  FitOptions fit;
  SplitConfig split;
  DataRequirements requirements;
  DifferentiatorConfig differentiator;
  /// Where xd, xdd come from (default: exact columns, else offline smoothing).
  FitDerivatives derivatives = FitDerivatives::kAutomatic;
  OfflineDerivativeConfig offline;
  bool uncertainty = true;
  /// Set: the verdict also says what the error is on this master.
  std::optional<MasterScale> master;
};

/// Runs the whole identification. Throws DataError for unusable data.
FitRun run_fit(const Recording& rec, const FrictionModel& initial, const std::string& initial_name,
               const FitWorkflowOptions& options = {});

nlohmann::json to_json(const ErrorMetrics& m);
nlohmann::json to_json(const std::vector<RegimeError>& regimes);
nlohmann::json to_json(const UncertaintyReport& u);
/// The whole report.json; "seconds" is `seconds`, plots as given.
nlohmann::json fit_report_json(const FitRun& run, const FitWorkflowOptions& options, double seconds,
                               const std::vector<std::string>& plots,
                               const std::string& plot_error);

/// Lines for the top of the params file: source, fit quality, date-free.
std::vector<std::string> fit_header_lines(const FitRun& run);

}  // namespace tsmh::estimator
