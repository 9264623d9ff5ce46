#pragma once
// How well a simulated friction matches the measured one, on a chosen set of
// samples, overall and per regime of the motion. Used by `tsm fit` (report on
// validation data) and `tsm gap` (where does the residual live).
//
//   rmse        sqrt(mean(e^2)), e = measured - model, N
//   p2p         max(e) - min(e), the paper's peak-to-peak error, N
//   fit_percent 100 (1 - ||e|| / ||y - mean(y)||)  (100 % = perfect,
//               0 % = no better than the mean, negative = worse)

#include <cmath>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "estimator/fit_data.hpp"

namespace tsmh::estimator {

struct ErrorMetrics {
  double rmse = std::nan("");
  double p2p = std::nan("");
  double fit_percent = std::nan("");
  double bias = std::nan("");  ///< mean(e), N
  std::size_t samples = 0;
};

/// Metrics over the samples where `select(i)` is true.
ErrorMetrics error_metrics(std::span<const double> measured, std::span<const double> model,
                           const std::function<bool(std::size_t)>& select);

/// Metrics over the samples of one role.
ErrorMetrics error_metrics(const FitData& data, std::span<const double> model, SampleRole role);

/// One slice of the data by the motion (or load, position, time).
struct RegimeError {
  std::string name;   ///< stable id, e.g. "accelerating", "near_reversal"
  std::string where;  ///< human description of the slice
  std::string group;  ///< what it slices by: acceleration, direction, speed, load, position, time
  ErrorMetrics metrics;
  /// This slice's share of the squared error, divided by its share of the
  /// samples: > 1 means the residual concentrates here.
  double concentration = std::nan("");
  double mean_error = std::nan("");  ///< mean(e) in the slice, N
  /// mean(e sgn(model)): how much the measured friction's magnitude exceeds
  /// the model's, N (> 0: the model's friction is too small there). Unlike
  /// mean(e) it does not cancel between the two directions.
  double magnitude_excess = std::nan("");
};

/// Thresholds the regimes are cut at, derived from the data.
struct RegimeThresholds {
  double reversal_speed = 0.0;  ///< |xd| below this is "near reversal", rad/s
  double speed_split = 0.0;     ///< median |xd| of the moving samples, rad/s
  double load_split = 0.0;      ///< median load, N
  double position_split = 0.0;  ///< median x, rad
  double time_split = 0.0;      ///< middle of the record, s
};

RegimeThresholds regime_thresholds(const FitData& data);

/// Per-regime errors on the samples of `role`: accelerating / decelerating
/// (|xd| growing or shrinking), positive / negative velocity, near reversal,
/// low / high speed, low / high load, low / high position, early / late.
std::vector<RegimeError> regime_errors(const FitData& data, std::span<const double> model,
                                       SampleRole role);

/// Integrated autocorrelation time of a sequence (samples): 1 + 2 sum of its
/// autocorrelation over the initial lags where it stays above 0.05. 1 for
/// white noise; N samples carry about N / tau independent errors.
double correlation_time(std::span<const double> r);

/// Autocorrelation of `r` at lag k (k >= 1), after removing the mean.
double autocorrelation(std::span<const double> r, std::size_t k);

/// Robust estimate of the white measurement noise on `y` (standard deviation):
/// median |second difference| / (0.6745 sqrt(6)). The smooth part of the
/// friction hardly contributes at 1 kHz; the torque-sensor noise does.
double noise_floor(std::span<const double> y);

}  // namespace tsmh::estimator
