#pragma once
// The virtual-slave command line, and turning it into plant parameters.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "bridge/node_link.hpp"
#include "virtual_tissue_slave/offline.hpp"
#include "virtual_tissue_slave/slave.hpp"
#include "virtual_tissue_slave/tissue.hpp"

namespace tsmh::virtual_tissue_slave::app {

struct CliOptions {
  // mode
  bool offline = false;
  bool print_tissue = false;
  bool list_scenarios = false;
  double duration_s = 0.0;  ///< 0: scenario default (offline) / until SIGINT (real time)
  std::string scenario = "sine";
  std::string output;
  int joint = 0;  ///< 0-based joint index: 0 = joint1 (the gripper), 1 = joint2
  bool exact_derivatives = false;
  bool truth_columns = false;
  std::uint64_t seed = 1;
  // plant
  std::string tissue;  ///< empty: scenario default (offline), nodule (real time)
  std::string contact = "kelvin-voigt";
  std::optional<double> surface_rad;
  std::string wrap, pretension;
  std::optional<double> mu;
  std::vector<std::string> effects;
  std::optional<double> reroute_at_s;
  std::string reroute_wrap;
  // sensors and controller
  std::optional<double> load_cell_noise_n;
  std::optional<int> motor_encoder_counts;
  bool no_joint_encoder = false;
  bool no_compensation = false;
  // real time
  /// --lcm-url, --prefix, --key, --insecure: a standalone node's link
  /// (bridge/node_link.hpp; docs/bridge.md "Authentication").
  bridge::NodeLinkOptions link;
  double command_timeout_s = 0.1;
  int rt_priority = 0;
  int cpu = -1;  ///< pin the 1 kHz loop thread to this CPU (-1: no pinning)
};

void add_options(CLI::App& app, CliOptions& o);

/// Everything the options decide, checked; throws std::invalid_argument with
/// the option name at fault.
struct Setup {
  SlaveParams params;
  TissueParams tissue;
  FrictionEffects effects;
  Reroute reroute;
  int joint_index = 0;
};
Setup make_setup(const CliOptions& o, const Scenario* scenario);

/// JSON (one object) describing `tissue` and its true stiffness values.
std::string tissue_json(const TissueParams& tissue);

}  // namespace tsmh::virtual_tissue_slave::app
