#pragma once
#include "cli_options.hpp"

namespace tsmh::virtual_tissue_slave::app {
/// `virtual-slave --offline`: returns the process exit code.
int run_offline_mode(const CliOptions& options);
}  // namespace tsmh::virtual_tissue_slave::app
