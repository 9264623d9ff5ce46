#include "estimator/simulate.hpp"

#include <cmath>

#include "estimator/corrections.hpp"

namespace tsmh::estimator {

std::vector<Motion> motion_from_recording(const Recording& rec, DerivativeSource source,
                                          const DifferentiatorConfig& diff) {
  const bool exact = source == DerivativeSource::kExact ||
                     (source == DerivativeSource::kAutomatic && rec.has_derivatives());
  if (exact && !rec.has_derivatives())
    throw DataError(rec.source, 0, "xd_in",
                    "exact derivatives requested but xd_in/xdd_in are missing");
  const bool has_load = rec.has_tau_in() && std::isfinite(rec.radius_m);
  const bool has_tensions = rec.T1.size() == rec.size() && rec.T3.size() == rec.size();
  std::vector<Motion> motion(rec.size());
  CorrectedDifferentiator d(diff);
  for (std::size_t i = 0; i < rec.size(); ++i) {
    Motion& m = motion[i];
    m.t = rec.t[i];
    m.x = rec.x_in[i];
    if (exact) {
      m.xd = rec.xd_in[i];
      m.xdd = rec.xdd_in[i];
      m.acc_sign = sign_of(m.xdd);
    } else {
      const Derivatives der = d.update(rec.t[i], rec.x_in[i]);
      m.xd = der.xd;
      m.xdd = der.xdd;
      m.acc_sign = der.acc_sign;
    }
    m.load = has_load ? std::fabs(rec.tau_in[i]) / rec.radius_m : 0.0;
    if (has_load) m.drive = rec.tau_in[i] / rec.radius_m;
    if (has_tensions) m.tension = 0.5 * (rec.T1[i] + rec.T3[i]);
    m.x_out = rec.x_out_at(i);
  }
  return motion;
}

void simulate_friction_into(FrictionModel& model, std::span<const Motion> motion,
                            std::span<double> out) noexcept {
  model.reset();
  if (motion.empty()) return;
  out[0] = model.friction();
  for (std::size_t i = 1; i < motion.size(); ++i) {
    out[i] = model.step(motion[i], motion[i].t - motion[i - 1].t);
  }
}

std::vector<double> simulate_friction(FrictionModel& model, std::span<const Motion> motion) {
  std::vector<double> out(motion.size());
  simulate_friction_into(model, motion, out);
  return out;
}

}  // namespace tsmh::estimator
