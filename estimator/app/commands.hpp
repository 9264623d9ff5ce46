#pragma once
// The `tsm` subcommands. Each lives in its own cmd_<name>.cpp and registers
// itself on the CLI11 app; main() only lists them.

#include <CLI/CLI.hpp>

#include "data_sources.hpp"
#include "lcm_log_source.hpp"

namespace tsmh::tsm_cli {

struct Context {
  DataSources sources;
  LcmLogSelection lcm_log;  ///< --joint/--prefix for LCM-log DATA (add_lcm_log_options)
};

void add_simulate_command(CLI::App& app, Context& ctx);
void add_convert_command(CLI::App& app, Context& ctx);
void add_fit_command(CLI::App& app, Context& ctx);
void add_gap_command(CLI::App& app, Context& ctx);

}  // namespace tsmh::tsm_cli
