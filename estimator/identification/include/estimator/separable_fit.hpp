#pragma once
// Identification of a model with distributed slip (distributed_slip.hpp),
// global by construction where the model is linear: its friction is linear in
// the element weights, the sliding coefficients and their tension, drive and
// load copies, so for given nonlinear values (the elements' spread, the velocity
// smoothing, the Stribeck speed, a Bouc-Wen part's parameters) the best
// weights are one least-squares problem, solved exactly (normal equations,
// a small ridge, nonnegative break forces by an active-set NNLS). Only the
// few nonlinear values are searched (a coarse grid, then NLopt's BOBYQA),
// and the number of elements is chosen by the Bayesian information
// criterion on the train samples.
//
// The distal load the load copies scale with is tau_in/R - F: in a fit it
// is the measured one (tau_out/R), so the problem stays linear; the
// deployed model solves the same relation for F exactly.

#include <span>
#include <vector>

#include "estimator/fit_data.hpp"
#include "estimator/identification.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {

/// True for a tendon-sheath model with distributed slip.
bool has_linear_block(const FrictionModel& model);

/// Least squares with some variables >= 0, on the normal equations G x = h
/// (G symmetric positive definite): Lawson and Hanson's active-set method
/// with the unconstrained variables always free. Exact for its problem.
std::vector<double> nonnegative_least_squares(const std::vector<double>& gram,
                                              const std::vector<double>& rhs,
                                              const std::vector<bool>& nonnegative);

/// Which copies the data can determine: tension copies when the mean
/// tension varies (its standard deviation on train samples above 0.2 N),
/// load copies when the measured distal load does (above 0.5 N), drive
/// copies when the signed distal load does (above 0.5 N: tip loads, which
/// free motion lacks).
struct CopiesInData {
  bool tension = false;
  bool load = false;
  bool drive = false;
};
CopiesInData copies_in_data(const FitData& data);

/// Both proximal tensions measured on every sample (T and u finite): what
/// the per-tendon element families (`tendon_widths`) scale with.
bool tensions_measured(const FitData& data);
/// Whether every sample has the distal angle (a joint encoder's x_out).
bool distal_angle_measured(const FitData& data);
/// The distal family tsm fit and tsm gap try: its size, and its positions
/// along the sheath (the share of x_out - x_in in its drive).
inline constexpr int kDistalCandidateElements = 8;
inline constexpr double kDistalPositions[] = {0.25, 0.5, 0.75, 1.0};
/// The two-position family tried after a kept single one: pairs of places
/// along the sheath, half the elements at each.
inline constexpr int kDistalPairElements = 12;
inline constexpr double kDistalPairs[][2] = {{1.0 / 3.0, 2.0 / 3.0}, {0.25, 0.75}, {0.5, 1.0}};

/// Sets the weights (and the copies `spec.slip` has on) of `spec` to the
/// least-squares optimum over the train samples (every `stride`-th one),
/// the Bouc-Wen part (if any) held as it is. Returns the train MSE of the
/// linear fit, N^2 (on the samples used).
double solve_slip_weights(TsmModelSpec& spec, const FitData& data, std::size_t stride = 1);

/// The whole identification of a model with distributed slip (identify()
/// calls it for method "lm" or "separable").
FitResult identify_separable(const FrictionModel& initial, const FitData& data,
                             const FitOptions& options);

}  // namespace tsmh::estimator
