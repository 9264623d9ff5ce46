// tsm-link: the LCM link's tools (docs/bridge.md "Authentication"):
// keygen creates the installation's link key, fingerprint tells which key a
// host would use.

#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "link_key_commands.hpp"
#include "tsmh/cli_words.hpp"
#include "tsmh/version.hpp"

int main(int argc, char** argv) {
  CLI::App app{"tsm-link: the LCM link key of a tsm-haptics installation"};
  app.set_version_flag("--version", tsmh::version_line("tsm-link"));
  app.require_subcommand(1);
  tsmh::bridge::add_keygen_command(app, "tsm-link");
  tsmh::bridge::add_fingerprint_command(app);
  if (const int rc = tsmh::cli_words::check_words(app, argc, argv)) return rc;
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const std::exception& e) {
    std::cerr << "tsm-link: error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
