#pragma once
// --config SERVER.yaml [--config-joint J] | --force-scale S --master-peak NM,
// shared by `tsm fit` and `tsm gap`: the master that renders the estimate,
// so the verdict can say what the error is in the surgeon's hand.

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "estimator/fit_workflow.hpp"

namespace tsmh::tsm_cli {

struct MasterScaleCliOptions {
  std::string config;
  std::string config_joint;  ///< name or index; empty: the first joint
  std::optional<double> force_scale;
  std::optional<double> master_peak;
};

void add_master_scale_options(CLI::App& cmd, MasterScaleCliOptions& o);

/// The master's scale from the options (flags win over the config's
/// values); nullopt when none is given. Throws on a bad config or joint.
std::optional<estimator::MasterScale> master_scale(const MasterScaleCliOptions& o);

}  // namespace tsmh::tsm_cli
