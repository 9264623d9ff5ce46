// tsm keygen [--output FILE] [--force]
// Creates the installation's LCM link key (docs/bridge.md, "Authentication"):
// 32 random bytes as 64 hex digits in a new file with mode 0600. Copy the same
// file to every host of the installation.

#include <cstdlib>
#include <iostream>
#include <memory>

#include "bridge/link_auth.hpp"
#include "bridge/link_security.hpp"
#include "commands.hpp"

namespace tsmh::tsm_cli {
namespace {

struct KeygenOptions {
  std::string output;
  bool force = false;
};

void run_keygen(const KeygenOptions& o) {
  std::filesystem::path file = o.output;
  if (file.empty()) {
    // The first place the programs look after --key and $TSMH_LINK_KEY.
    file =
        bridge::default_key_locations(std::getenv("XDG_CONFIG_HOME"), std::getenv("HOME")).front();
  }
  const auto key = bridge::LinkKey::generate();
  key.save(file, o.force);
  std::cout << file.string() << "\n";
  std::cerr << "tsm keygen: new link key " << file.string() << " (mode 0600, fingerprint "
            << key.fingerprint()
            << "); copy it to every host of this installation (the same path, or --key / $"
            << bridge::kLinkKeyEnv << ")\n";
}

}  // namespace

void add_keygen_command(CLI::App& app, Context& /*ctx*/) {
  auto opts = std::make_shared<KeygenOptions>();
  auto* cmd = app.add_subcommand(
      "keygen", "Create the LCM link key that authenticates haptic-server, slaves and masters");
  cmd->add_option("--output", opts->output,
                  "Key file to create (default: $XDG_CONFIG_HOME/tsmh/link.key or "
                  "~/.config/tsmh/link.key; /etc/tsmh/link.key for a whole host)");
  cmd->add_flag("--force", opts->force,
                "Replace an existing key (every peer holding the old one loses the link)");
  cmd->callback([opts] { run_keygen(*opts); });
}

}  // namespace tsmh::tsm_cli
