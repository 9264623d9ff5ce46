#pragma once
// --free-motion and its options, shared by `tsm fit` and `tsm gap`
// (docs/identification.md "Free-motion identification").

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "estimator/free_motion.hpp"

namespace tsmh::tsm_cli {

struct FreeMotionCliOptions {
  bool enabled = false;
  std::optional<double> joint_inertia;
  std::optional<double> joint_damping;
};

void add_free_motion_options(CLI::App& cmd, FreeMotionCliOptions& o);

struct LoadedFitData {
  estimator::Recording recording;  ///< tau_out filled in for free motion
  std::optional<estimator::FreeMotionData> free_motion;
  std::vector<std::string> notes;
};

/// Reads DATA; with --free-motion tau_out is not required and is replaced by
/// the free joint's distal torque (contact refused with a DataError).
LoadedFitData load_fit_recording(const Context& ctx, const std::string& data,
                                 std::optional<double> radius, const FreeMotionCliOptions& o);

nlohmann::json free_motion_json(const estimator::FreeMotionData& f);

}  // namespace tsmh::tsm_cli
