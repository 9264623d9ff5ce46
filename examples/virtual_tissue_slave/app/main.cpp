// virtual-slave: the virtual tissue slave. Real time over LCM by default,
// or --offline to write recorded data for `tsm fit` / `tsm gap`.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "cli_options.hpp"
#include "files/file_size_limit.hpp"
#include "offline_mode.hpp"
#include "realtime_mode.hpp"
#include "tsmh/cli_words.hpp"
#include "tsmh/version.hpp"
#include "virtual_tissue_slave/scenario.hpp"

int main(int argc, char** argv) {
  namespace app = tsmh::virtual_tissue_slave::app;
  namespace vts = tsmh::virtual_tissue_slave;
  CLI::App cli{
      "virtual-slave: a two-joint tendon-sheath slave with tissue at the tool (physics, "
      "sensors, controller). Real time at 1 kHz over LCM (MASTER_COMMAND in; SLAVE_STATE, "
      "SLAVE_TRUTH out), or --offline to write a recording. See docs/virtual-slave.md."};
  cli.set_version_flag("--version", tsmh::version_line("virtual-slave"));
  // A file-size limit fails the write with a message (and no temporary file
  // left), instead of SIGXFSZ killing the program.
  tsmh::files::ignore_file_size_signal();
  app::CliOptions options;
  app::add_options(cli, options);
  // A typo is named with the nearest option (tsmh/cli_words.hpp).
  if (const int rc = tsmh::cli_words::check_words(cli, argc, argv)) return rc;
  CLI11_PARSE(cli, argc, argv);
  try {
    if (options.list_scenarios) {
      for (const auto& name : vts::scenario_names()) {
        const auto s = vts::make_scenario(name);
        std::printf("%-10s %s (default %.0f s)\n", name.c_str(), s.description.c_str(),
                    s.default_duration_s);
      }
      return 0;
    }
    if (options.print_tissue) {
      const vts::Scenario scenario = vts::make_scenario(options.scenario);
      const app::Setup setup = app::make_setup(options, options.offline ? &scenario : nullptr);
      std::printf("%s\n", app::tissue_json(setup.tissue).c_str());
      return 0;
    }
    return options.offline ? app::run_offline_mode(options) : app::run_realtime_mode(options);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "virtual-slave: error: %s\n", e.what());
    return 1;
  }
}
