#include "link_key_commands.hpp"

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>

#include "bridge/link_auth.hpp"
#include "bridge/link_security.hpp"

namespace tsmh::bridge {
namespace {

struct KeygenOptions {
  std::string output;
  bool force = false;
};

void run_keygen(const KeygenOptions& o, const std::string& program) {
  std::filesystem::path file = o.output;
  if (file.empty()) {
    // The first place the programs look after --key and $TSMH_LINK_KEY.
    file = default_key_locations(std::getenv("XDG_CONFIG_HOME"), std::getenv("HOME")).front();
  }
  const auto key = LinkKey::generate();
  key.save(file, o.force);
  std::cout << file.string() << "\n";
  std::cerr << program << ": new link key " << file.string() << " (mode 0600, fingerprint "
            << key.fingerprint()
            << "); copy it to every host of this installation (the same path, or --key / $"
            << kLinkKeyEnv << ")\n";
}

void run_fingerprint(const std::string& key_flag) {
  const auto file = find_key_file(key_flag, std::getenv(kLinkKeyEnv),
                                  std::getenv("XDG_CONFIG_HOME"), std::getenv("HOME"));
  if (!file) {
    std::string where;
    for (const auto& p : default_key_locations(std::getenv("XDG_CONFIG_HOME"), std::getenv("HOME")))
      where += (where.empty() ? "" : ", ") + p.string();
    throw LinkKeyError(std::string("no link key (looked at --key, $") + kLinkKeyEnv + ", " + where +
                       "); create one with `tsm-link keygen`");
  }
  const auto key = LinkKey::load(*file);
  std::cout << key.fingerprint() << "  " << file->string() << "\n";
}

}  // namespace

void add_keygen_command(CLI::App& app, const std::string& program) {
  auto opts = std::make_shared<KeygenOptions>();
  auto* cmd = app.add_subcommand(
      "keygen", "Create the LCM link key that authenticates haptic-server, slaves and masters");
  cmd->add_option("--output", opts->output,
                  "Key file to create (default: $XDG_CONFIG_HOME/tsmh/link.key or "
                  "~/.config/tsmh/link.key; /etc/tsmh/link.key for a whole host)");
  cmd->add_flag("--force", opts->force,
                "Replace an existing key (every peer holding the old one loses the link)");
  cmd->callback([opts, program] { run_keygen(*opts, program + " keygen"); });
}

void add_fingerprint_command(CLI::App& app) {
  auto key = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand(
      "fingerprint",
      "Print the fingerprint of the link key the programs would use, and its file; equal "
      "fingerprints on two hosts mean the same key");
  cmd->add_option("--key", *key, kKeyOptionHelp);
  cmd->callback([key] { run_fingerprint(*key); });
}

}  // namespace tsmh::bridge
