#pragma once
// Plots for the identification and model-gap reports, drawn by gnuplot
// (Debian gnuplot-nox; PNG through pngcairo, SVG where that is missing). Each
// plot keeps its data file and script beside the image so it can be redrawn
// or restyled. A missing or failing gnuplot is reported, not fatal: the
// numbers in report.json do not depend on it.

#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "estimator/fit_data.hpp"

namespace tsmh::estimator {

struct PlotOutcome {
  std::vector<std::string> files;  ///< images written (file names within the directory)
  std::string error;               ///< empty on success
};

/// A named model output to draw against the measurement.
struct PlotCurve {
  std::string title;
  std::span<const double> friction;  ///< N, one per sample of the data
};

/// Writes into `dir`, files prefixed with `prefix`:
///   PREFIX_friction.png   measured and model friction over time (validation blocks shaded)
///   PREFIX_hysteresis.png friction vs velocity (the hysteresis loops), measured and models
///   PREFIX_residual.png   measured - model over time, per curve
/// each with its script (PREFIX_friction.gp, ...); PREFIX_plot_data.csv holds
/// the samples (at most ~20000 rows), PREFIX_residual_data.csv each curve's
/// residual as drawn (its smallest and largest value per pixel column).
PlotOutcome plot_friction(const std::filesystem::path& dir, const std::string& prefix,
                          const FitData& data, const std::vector<PlotCurve>& curves,
                          const std::string& title);

/// Bar chart of a residual's concentration per regime (before/after), for
/// the gap report: PREFIX_regimes.png.
struct RegimeBars {
  std::vector<std::string> regimes;
  std::vector<std::string> series;        ///< e.g. "base", "final"
  std::vector<std::vector<double>> rmse;  ///< [series][regime], N
};
PlotOutcome plot_regimes(const std::filesystem::path& dir, const std::string& prefix,
                         const RegimeBars& bars, const std::string& title);

/// A curve y(x) as points: NAME.png with NAME.csv and NAME.gp beside it
/// (e.g. the friction a gap effect adds against its variable).
PlotOutcome plot_xy(const std::filesystem::path& dir, const std::string& name,
                    const std::vector<std::pair<double, double>>& points, const std::string& xlabel,
                    const std::string& ylabel, const std::string& title);

/// Runs gnuplot on a script file; returns "" or what went wrong (with
/// gnuplot's own message).
std::string run_gnuplot(const std::filesystem::path& script);
/// The same for several scripts at once, each in its own gnuplot; returns
/// the first failure in `scripts`' order.
std::string run_gnuplot(const std::vector<std::filesystem::path>& scripts);

/// The gnuplot terminal to use: "pngcairo" when available, else "svg".
std::string plot_terminal();

}  // namespace tsmh::estimator
