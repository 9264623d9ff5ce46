#include "scoring.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "estimator/distal_estimator.hpp"

namespace tsmh::accuracy {

namespace {

OnlineScore score_estimate(const Scored& s, const std::vector<double>& tip_est) {
  const auto& rec = s.rec;
  OnlineScore out;
  double se = 0, se_c = 0, se_f = 0, fe = 0, fe_c = 0, fe_f = 0;
  std::size_t n = 0;
  const double from = rec.t.front() + kWarmUpS;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    if (rec.t[i] < from) continue;
    out.peak = std::max(out.peak, std::fabs(s.tau_out_true[i]));
    if (!std::isfinite(tip_est[i])) {
      ++out.invalid;
      continue;
    }
    const double e = tip_est[i] - s.tau_out_true[i];
    const double f = rec.tau_in[i] - rec.radius_m * s.friction_true[i] - s.tau_out_true[i];
    ++n;
    se += e * e;
    fe += f * f;
    if (!s.contact.empty() && s.contact[i] != 0) {
      se_c += e * e;
      fe_c += f * f;
      ++out.model.contact_samples;
    } else {
      se_f += e * e;
      fe_f += f * f;
      ++out.model.free_samples;
    }
  }
  const auto rms = [](double sum, std::size_t count) {
    return count == 0 ? std::numeric_limits<double>::quiet_NaN()
                      : std::sqrt(sum / static_cast<double>(count));
  };
  out.model.all = rms(se, n);
  out.model.contact = rms(se_c, out.model.contact_samples);
  out.model.free = rms(se_f, out.model.free_samples);
  out.floor = out.model;
  out.floor.all = rms(fe, n);
  out.floor.contact = rms(fe_c, out.model.contact_samples);
  out.floor.free = rms(fe_f, out.model.free_samples);
  return out;
}

}  // namespace

OnlineScore score_online(const estimator::FrictionModel& model, const Scored& s,
                         const estimator::DifferentiatorConfig& diff,
                         const estimator::CorrectionsConfig& corrections) {
  const auto& rec = s.rec;
  // haptic-server's defaults: DifferentiatorConfig{} (its per-joint
  // settings default to these) and the free-tip start.
  estimator::DistalTorqueEstimator est(model.clone(), rec.radius_m, diff,
                                       estimator::StartState::kFreeTip, corrections);
  const bool tensions = !rec.T1.empty() && !rec.T3.empty();
  std::vector<double> tip(rec.size());
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const estimator::Estimate e =
        tensions ? est.update_tensions(rec.t[i], rec.x_in[i], rec.T1[i], rec.T3[i], rec.x_out_at(i))
                 : est.update(rec.t[i], rec.x_in[i], rec.tau_in[i],
                              std::numeric_limits<double>::quiet_NaN(), rec.x_out_at(i));
    tip[i] = e.valid ? e.tau_out_est : std::numeric_limits<double>::quiet_NaN();
  }
  return score_estimate(s, tip);
}

OnlineScore score_naive(const Scored& s) {
  return score_estimate(s, s.rec.tau_in);
}

double friction_sensor_floor(const Scored& s) {
  const auto& rec = s.rec;
  double se = 0.0;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const double measured = (rec.tau_in[i] - rec.tau_out[i]) / rec.radius_m;
    se += (measured - s.friction_true[i]) * (measured - s.friction_true[i]);
  }
  return std::sqrt(se / static_cast<double>(rec.size()));
}

}  // namespace tsmh::accuracy
