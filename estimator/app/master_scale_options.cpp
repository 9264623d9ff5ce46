#include "master_scale_options.hpp"

#include <cmath>
#include <stdexcept>

#include "haptics/server_config.hpp"

namespace tsmh::tsm_cli {

void add_master_scale_options(CLI::App& cmd, MasterScaleCliOptions& o) {
  cmd.add_option("--config", o.config,
                 "haptic-server's config: the verdict then gives the error on the master "
                 "(force_scale) and as a share of its peak (max_torque_nm)");
  cmd.add_option("--config-joint", o.config_joint,
                 "which joint of --config the data are from: name or index (default: the first)");
  cmd.add_option("--force-scale", o.force_scale,
                 "master N m per slave N m (as force_scale in the server's config)")
      ->check(CLI::PositiveNumber);
  cmd.add_option("--master-peak", o.master_peak, "the master joint's peak torque, N m")
      ->check(CLI::PositiveNumber);
}

std::optional<estimator::MasterScale> master_scale(const MasterScaleCliOptions& o) {
  if (o.config.empty() && !o.force_scale && !o.master_peak) return std::nullopt;
  estimator::MasterScale m;
  if (!o.config.empty()) {
    const haptics::ServerConfig cfg = haptics::load_server_config(o.config);
    std::size_t j = 0;
    if (!o.config_joint.empty()) {
      bool found = false;
      for (std::size_t k = 0; k < cfg.joints.size() && !found; ++k) {
        if (cfg.joints[k].name == o.config_joint || std::to_string(k) == o.config_joint) {
          j = k;
          found = true;
        }
      }
      if (!found)
        throw std::invalid_argument("--config-joint '" + o.config_joint + "': no such joint in " +
                                    o.config);
    }
    if (j >= cfg.joints.size()) throw std::invalid_argument(o.config + ": no joints");
    m.force_scale = cfg.loop.force[j].scale;
    m.peak_nm = cfg.loop.limits[j].max_torque_nm;
    m.source = o.config + ", joint " + cfg.joints[j].name;
  }
  if (o.force_scale) m.force_scale = *o.force_scale;
  if (o.master_peak) m.peak_nm = *o.master_peak;
  if (o.force_scale || o.master_peak)
    m.source =
        o.config.empty() ? std::string("from the command line") : m.source + ", flags override";
  if (!std::isfinite(m.force_scale))
    throw std::invalid_argument("--master-peak needs --force-scale (or --config)");
  return m;
}

}  // namespace tsmh::tsm_cli
