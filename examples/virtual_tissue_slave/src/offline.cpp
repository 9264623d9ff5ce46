#include "virtual_tissue_slave/offline.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>

namespace tsmh::virtual_tissue_slave {

void validate(const Reroute& rr) {
  if (std::isnan(rr.at_s)) return;
  if (!(std::isfinite(rr.at_s) && rr.at_s >= 0))
    throw std::invalid_argument("--reroute-at must be >= 0 s");
  if (!(std::isfinite(rr.sheath1_wrap_rad) && rr.sheath1_wrap_rad >= 0))
    throw std::invalid_argument("--reroute-wrap must be >= 0 rad");
  if (!std::isnan(rr.sheath2_wrap_rad) &&
      !(std::isfinite(rr.sheath2_wrap_rad) && rr.sheath2_wrap_rad >= 0))
    throw std::invalid_argument("--reroute-wrap: the second wrap must be >= 0 rad");
}

void apply_reroute(VirtualSlave& slave, const SlaveParams& params, const Reroute& rr, int joint) {
  const auto& base = params.joints[static_cast<std::size_t>(joint)];
  const double f1 = base.tendon1.wrap_rad > 0 ? rr.sheath1_wrap_rad / base.tendon1.wrap_rad : 1.0;
  const double w2 =
      std::isnan(rr.sheath2_wrap_rad) ? base.tendon2.wrap_rad * f1 : rr.sheath2_wrap_rad;
  const double f2 = base.tendon2.wrap_rad > 0 ? w2 / base.tendon2.wrap_rad : 1.0;
  for (int j = 0; j < kJoints; ++j) {
    const auto& jp = params.joints[static_cast<std::size_t>(j)];
    slave.joint(j).set_wraps(jp.tendon1.wrap_rad * f1, jp.tendon2.wrap_rad * f2);
  }
}

OfflineStats run_offline(const SlaveParams& params, const OfflineOptions& options,
                         const std::function<void(const SlaveSample&)>& sink) {
  if (!(std::isfinite(options.duration_s) && options.duration_s > 0))
    throw std::invalid_argument("--duration must be > 0 s");
  if (!(std::isfinite(options.settle_s) && options.settle_s >= 0))
    throw std::invalid_argument("settle time must be >= 0 s");
  if (options.joint < 0 || options.joint >= kJoints)
    throw std::invalid_argument("--joint must be 0 or 1");
  const Reroute& rr = options.reroute;
  validate(rr);
  const bool reroute = !std::isnan(rr.at_s);

  SlaveParams p = params;
  TissueParams tissue = options.tissue ? *options.tissue : tissue_preset(options.scenario.tissue);
  if (!options.tissue) tissue.surface_rad = options.scenario.surface_rad;
  for (auto& j : p.joints)
    j.tissue = tissue;
  VirtualSlave slave(p, options.seed);
  for (int j = 0; j < kJoints; ++j)
    slave.joint(j).set_effects(options.effects);

  const Scenario& sc = options.scenario;
  const auto refs_at = [&](double t) {
    return std::array<double, kJoints>{sc.reference(t, 0), sc.reference(t, 1)};
  };

  OfflineStats stats;
  const auto start = std::chrono::steady_clock::now();
  slave.settle(refs_at(0.0), options.settle_s);
  const long n = std::lround(options.duration_s / p.control_period_s);
  bool rerouted = false;
  for (long k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) * p.control_period_s;
    if (reroute && !rerouted && t >= rr.at_s) {
      apply_reroute(slave, p, rr, options.joint);
      rerouted = true;
    }
    sink(slave.tick(refs_at(t)));
    ++stats.samples;
  }
  stats.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  stats.simulated_s = static_cast<double>(n) * p.control_period_s + options.settle_s;
  for (int j = 0; j < kJoints; ++j)
    stats.fallback_solves += slave.joint(j).fallback_solves();
  return stats;
}

}  // namespace tsmh::virtual_tissue_slave
