// tsm: the estimator's command line (docs/data-formats.md, docs/identification.md): simulate, fit,
// gap, convert; keygen is an alias of `tsm-link keygen` (the LCM link key, docs/bridge.md).

#include <iostream>

#include "commands.hpp"
#include "estimator/model_io.hpp"
#include "estimator/table.hpp"
#include "files/file_size_limit.hpp"
#include "link_key_commands.hpp"
#include "output_checks.hpp"
#include "tsmh/cli_words.hpp"
#include "tsmh/version.hpp"

int main(int argc, char** argv) {
  using namespace tsmh::tsm_cli;
  // Under a file-size limit a write fails with EFBIG and is reported, the
  // temporary file removed, instead of SIGXFSZ killing tsm silently.
  tsmh::files::ignore_file_size_signal();
  CLI::App app{
      "tsm: tendon-sheath friction models: simulate, identify, find model gaps; LCM link key"};
  app.set_version_flag("--version", tsmh::version_line("tsm"));
  app.require_subcommand(1);
  Context ctx;
  ctx.sources.add(lcm_log_source(ctx.lcm_log));
  add_simulate_command(app, ctx);
  add_convert_command(app, ctx);
  add_fit_command(app, ctx);
  add_gap_command(app, ctx);
  // The link key belongs to the link's tools (tsm-link); kept here as an alias.
  tsmh::bridge::add_keygen_command(app, "tsm");
  // A typo is named with the nearest valid word before CLI11 reports the
  // first rule it breaks (e.g. "A subcommand is required" for 'tsm fitt').
  if (const int rc = tsmh::cli_words::check_words(app, argc, argv)) return rc;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const tsmh::estimator::DataError& e) {
    std::cerr << "tsm: error: " << e.what() << "\n";
    return 2;
  } catch (const UsageError& e) {
    std::cerr << "tsm: error: " << e.what() << "\n";
    return 2;
  } catch (const tsmh::estimator::ParamsError& e) {
    std::cerr << "tsm: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "tsm: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
