#pragma once
// `tsm fit` as a library call: prepare the data, identify, score on
// validation (overall and per regime), estimate the parameters' uncertainty,
// judge the fit, and build report.json (docs/data-formats.md). The CLI adds only
// file handling, so tests exercise exactly what users run.

#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "estimator/fit_data.hpp"
#include "estimator/fit_metrics.hpp"
#include "estimator/identification.hpp"
#include "estimator/uncertainty.hpp"

namespace tsmh::estimator {

struct FitVerdict {
  std::string grade;   ///< "good", "fair" or "poor"
  std::string reason;  ///< one sentence with the numbers
};

/// good: validation RMSE within `good_ratio` (1.2) x the noise floor
/// estimated from the data (`noise`), no free parameter at a bound, and no
/// sign of over-fitting (validation RMSE within 1.5x train). poor: validation
/// fit < 50 %. fair otherwise. The reason gives the raw
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
