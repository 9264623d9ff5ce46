#pragma once
// How the judge scores one model on one recording: the deployed estimator
// run sample by sample as haptic-server runs it, its tip torque against the
// true tip torque, beside the floor that only sensor noise leaves.

#include <cstddef>
#include <functional>
#include <vector>

#include "estimator/corrections.hpp"
#include "estimator/differentiator.hpp"
#include "estimator/friction_model.hpp"
#include "sources.hpp"

namespace tsmh::accuracy {

/// RMSE of an estimate of the tip torque, N m, over all scored samples and
/// split into those in contact and in free motion (NaN where none).
struct TipError {
  double all = 0.0, contact = 0.0, free = 0.0;
  std::size_t contact_samples = 0, free_samples = 0;
};

struct OnlineScore {
  TipError model;           ///< the deployed estimator with this model
  TipError floor;           ///< tau_in - R F_true: the true friction, sensor noise alone left
  double peak = 0;          ///< N m, peak |true tip torque| over the scored samples
  std::size_t invalid = 0;  ///< samples the estimator rejected (not scored)
  double pct(double v) const { return 100.0 * v / peak; }
  double ratio() const { return model.all / floor.all; }
};

/// Samples before this long after a recording's first are not scored (the
/// estimator starts from rest there).
inline constexpr double kWarmUpS = 1.0;

/// The deployed DistalTorqueEstimator (DifferentiatorConfig and start state
/// as haptic-server's defaults, unless `diff` says otherwise: a variant the
/// judge compares), fed the tensions where the recording has them
/// (update_tensions, as the server is) and tau_in otherwise.
OnlineScore score_online(const estimator::FrictionModel& model, const Scored& s,
                         const estimator::DifferentiatorConfig& diff = {},
                         const estimator::CorrectionsConfig& corrections = {});
/// The naive estimate (tau_in taken as the tip torque) scored alike.
OnlineScore score_naive(const Scored& s);

/// RMS of the measured friction (tau_in - tau_out)/R less the true friction:
/// the sensor floor a fit's validation RMSE is held to, N.
double friction_sensor_floor(const Scored& s);

}  // namespace tsmh::accuracy
