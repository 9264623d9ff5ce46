#pragma once
// How much to trust identified parameters: the Jacobian of the simulated
// friction with respect to the free parameters at the optimum (central finite
// differences, one-sided at a bound) gives the linearised covariance
//   cov = s^2 tau (J^T J)^-1,  s^2 = SSR / (N - p),
// where tau, the integrated autocorrelation time of the residual, widens it
// for residuals that are not white (model error is correlated in time, so N
// samples carry fewer than N independent errors). From it: standard errors,
// correlations, and warnings for parameters the data do not pin down.

#include <cmath>
#include <string>
#include <vector>

#include "estimator/fit_data.hpp"
#include "estimator/friction_model.hpp"

namespace tsmh::estimator {

struct ParameterEstimate {
  std::string name;
  std::string unit;
  double value = 0.0;
  double std_error = std::nan("");  ///< NaN for fixed or not estimable parameters
  double lower = 0.0;
  double upper = 0.0;
  bool fixed = false;
  bool at_bound = false;
  bool well_identified = false;  ///< free, not at a bound, std small, not degenerate
};

/// "at its lower bound (value 0.009286, bound 0)": the one wording of every
/// report of a parameter at a bound (the value and the bound both named).
std::string at_bound_text(const ParameterEstimate& p);

/// What a parameter at a bound does to the model and what to do about it
/// (a term's size at 0 or the bump of a term the slave lacks pushed to its
/// ceiling: the term is likely absent, drop it).
std::string bound_consequence(const ParameterEstimate& p);

struct UncertaintyReport {
  std::vector<ParameterEstimate> parameters;  ///< all, in parameters() order
  std::vector<std::string> free_names;        ///< rows/columns of `correlation`
  std::vector<std::vector<double>> correlation;
  double residual_std = std::nan("");      ///< s, N
  double correlation_time = std::nan("");  ///< tau, samples
  double condition_number = std::nan("");  ///< of the column-scaled J^T J
  std::vector<std::string> warnings;
  std::vector<std::string> notes;  ///< facts about the model (fixed parameters and why)
};

struct UncertaintyOptions {
  double relative_step = 1e-3;    ///< finite-difference step, relative to max(|v|, 1e-3 range)
  double max_relative_std = 0.5;  ///< std / |value| above this: poorly identified
  double max_range_std = 0.25;    ///< std / (upper - lower) above this: poorly identified
  double max_correlation = 0.95;  ///< |r| above this: warned as a pair
  double bound_margin = 1e-3;     ///< within this fraction of the range: at a bound
};

/// The warnings as one line per problem, for a reader: parameters the data do
/// not pin down are grouped with the parameters they are strongly correlated
/// with and with the other doubtful parameters of the same term, e.g.
/// "acceleration_dependence.mu2, kappa2: poorly identified (standard error
/// 570 %, 620 % of the value), correlated r = -0.97: the data determine mainly
/// a combination". Warnings about no parameter pass through unchanged.
std::vector<std::string> grouped_warnings(const UncertaintyReport& report,
                                          const UncertaintyOptions& options = {});

/// Evaluates the uncertainty of `fitted` on the train samples of `data`.
UncertaintyReport estimate_uncertainty(const FrictionModel& fitted, const FitData& data,
                                       const UncertaintyOptions& options = {});

}  // namespace tsmh::estimator
