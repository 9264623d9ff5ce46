#pragma once
// The `tsm` subcommands. Each lives in its own cmd_<name>.cpp and registers
// itself on the CLI11 app; main() only lists them.

#include <CLI/CLI.hpp>

#include "data_sources.hpp"

namespace tsmh::tsm_cli {

struct Context {
  DataSources sources;
};

void add_simulate_command(CLI::App& app, Context& ctx);

}  // namespace tsmh::tsm_cli
