#pragma once
#include "cli_options.hpp"

namespace tsmh::virtual_tissue_slave::app {
/// The 1 kHz LCM node: returns the process exit code.
int run_realtime_mode(const CliOptions& options);
}  // namespace tsmh::virtual_tissue_slave::app
