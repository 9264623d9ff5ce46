#pragma once
// Runs the virtual slave on a scenario as fast as the CPU allows, with the
// hidden effects (extra drag, load-independent friction, position dependence,
// sheath re-routing mid-run) switched as asked.

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>

#include "virtual_tissue_slave/joint_plant.hpp"
#include "virtual_tissue_slave/scenario.hpp"
#include "virtual_tissue_slave/slave.hpp"
#include "virtual_tissue_slave/tissue.hpp"

namespace tsmh::virtual_tissue_slave {

/// A change of every sheath's wrap at a given time (the endoscope bends).
struct Reroute {
  double at_s = std::numeric_limits<double>::quiet_NaN();  ///< NaN: never
  double sheath1_wrap_rad = 0.0;  ///< new wrap of sheath 01 of the selected joint
  /// New wrap of sheath 02; NaN scales it by the same factor as sheath 01.
  double sheath2_wrap_rad = std::numeric_limits<double>::quiet_NaN();
};

/// Throws std::invalid_argument naming the option (--reroute-at, --reroute-wrap).
void validate(const Reroute& reroute);

/// Re-routes now: the sheaths of joint index `joint` get the reroute's
/// absolute wraps, the other joint's sheaths bend by the same factors
/// (relative to their wraps in `params`).
void apply_reroute(VirtualSlave& slave, const SlaveParams& params, const Reroute& reroute,
                   int joint);

struct OfflineOptions {
  Scenario scenario = make_scenario("sine");
  double duration_s = 30.0;
  /// Tissue for both joints; empty: the scenario's default preset.
  std::optional<TissueParams> tissue;
  FrictionEffects effects;
  Reroute reroute;
  int joint = 0;  ///< joint index the reroute's absolute wraps refer to (others scale alike)
  std::uint64_t seed = 1;
  double settle_s = 0.5;  ///< pretension settles at the start pose before t = 0
};

struct OfflineStats {
  long samples = 0;
  double simulated_s = 0.0;
  double wall_s = 0.0;
  long fallback_solves = 0;  ///< tendon solves that needed the slow path
  double realtime_factor() const { return wall_s > 0 ? simulated_s / wall_s : 0.0; }
};

/// Builds the slave from `params` and the options, settles it, then calls
/// `sink` with every control-period sample for the duration. Throws
/// std::invalid_argument for bad options (naming the option).
OfflineStats run_offline(const SlaveParams& params, const OfflineOptions& options,
                         const std::function<void(const SlaveSample&)>& sink);

}  // namespace tsmh::virtual_tissue_slave
