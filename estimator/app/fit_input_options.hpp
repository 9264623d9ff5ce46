#pragma once
// The options `tsm fit` and `tsm gap` share, declared once: the recording
// (DATA, --radius, --free-motion and its joint, an LCM log's key), how its
// derivatives are made, the optimiser's seed and threads, and the master
// that gives the error its meaning in the hand.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <string>

#include "commands.hpp"
#include "free_motion_options.hpp"
#include "master_scale_options.hpp"

namespace tsmh::tsm_cli {

struct FitInputCliOptions {
  std::string data;
  std::optional<double> radius;
  std::uint64_t seed = 1;
  int threads = 0;
  std::string derivatives = "auto";
  FreeMotionCliOptions free_motion;
  MasterScaleCliOptions master;
};

/// DATA and --radius.
void add_recording_options(CLI::App& cmd, FitInputCliOptions& o);
/// --seed, --threads, --derivatives, the free-motion, master and LCM-log options.
void add_fit_input_options(CLI::App& cmd, FitInputCliOptions& o, Context& ctx);

}  // namespace tsmh::tsm_cli
