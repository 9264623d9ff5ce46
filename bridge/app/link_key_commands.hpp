#pragma once
// The link key's commands, defined once for every program that offers them:
// `tsm-link keygen` / `tsm-link fingerprint`, and `tsm keygen`, which stays as
// an alias of the first (docs/bridge.md "Authentication").

#include <CLI/CLI.hpp>
#include <string>

namespace tsmh::bridge {

/// Adds `keygen [--output FILE] [--force]`: 32 random bytes as 64 hex digits
/// in a new file with mode 0600, by default at the first place the programs
/// look after --key and $TSMH_LINK_KEY. Prints the file on stdout and its
/// fingerprint on stderr. `program` names the caller in its messages.
void add_keygen_command(CLI::App& app, const std::string& program);

/// Adds `fingerprint [--key FILE]`: the fingerprint of the key the programs
/// would use (the same search as theirs), so that two hosts can tell whether
/// they share a key without showing it.
void add_fingerprint_command(CLI::App& app);

}  // namespace tsmh::bridge
