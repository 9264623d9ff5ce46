#pragma once
// How a program decides whether its LCM link is authenticated: find the
// link key, or run without one only where that is safe (docs/bridge.md,
// "Authentication"). Every program that talks over the bridge calls
// resolve_link_security() with its --key and --insecure options.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "bridge/link_auth.hpp"

namespace tsmh::bridge {

/// The environment variable naming a key file (search step 2).
inline constexpr const char* kLinkKeyEnv = "TSMH_LINK_KEY";

/// Search steps 3 and 4: $XDG_CONFIG_HOME/tsmh/link.key (else
/// $HOME/.config/tsmh/link.key), then /etc/tsmh/link.key. The first is where
/// `tsm-link keygen` writes by default.
std::vector<std::filesystem::path> default_key_locations(const char* xdg_config_home,
                                                         const char* home);

/// The key file to use: `flag` (--key) if non-empty, else `env` (TSMH_LINK_KEY)
/// if non-empty, else the first default location that exists; nullopt when
/// none. A file named by the flag or the variable must exist (LinkKeyError
/// otherwise: a typo must not silently fall back to another key or none).
std::optional<std::filesystem::path> find_key_file(std::string_view flag, const char* env,
                                                   const char* xdg_config_home, const char* home);

/// True for URLs whose traffic cannot come from another host: memq:// (one
/// process), file:// (a log), and udpm with ttl=0, whose receive socket the
/// bridge restricts to this host (bridge/host_only.hpp; a Receiver that
/// cannot do so refuses to start). Any other udpm URL is reachable from the
/// network. Throws LcmUrlError for a URL the strict parser refuses
/// (lcmtypes/lcm_url.hpp): "?ttl=0&ttl=1" is not host-local, it is an error.
bool is_host_local_url(std::string_view url);

/// The --key option's help, the same for every program (the search order
/// of find_key_file()).
inline constexpr const char* kKeyOptionHelp =
    "LCM link key file (default: $TSMH_LINK_KEY, ~/.config/tsmh/link.key, "
    "/etc/tsmh/link.key; create one with `tsm-link keygen`)";

struct LinkSecurityOptions {
  std::string key_file;   ///< --key FILE
  bool insecure = false;  ///< --insecure: allow no key on a network URL
};

struct LinkSecurity {
  std::shared_ptr<const LinkKey> key;  ///< null: unauthenticated
  std::string notice;  ///< one line for stderr: which key (fingerprint), or why none
};

/// Finds and loads the key (find_key_file with the real environment). With
/// no key: allowed on a host-local URL, or with options.insecure; otherwise
/// throws LinkKeyError saying where it looked and how to create a key.
/// A URL the strict parser refuses throws LcmUrlError, key or not.
LinkSecurity resolve_link_security(std::string_view url, const LinkSecurityOptions& options);

}  // namespace tsmh::bridge
