#include "bridge/link_security.hpp"

#include <cstdlib>
#include <system_error>

#include "lcmtypes/lcm_url.hpp"

namespace tsmh::bridge {

std::vector<std::filesystem::path> default_key_locations(const char* xdg_config_home,
                                                         const char* home) {
  std::vector<std::filesystem::path> out;
  if (xdg_config_home != nullptr && xdg_config_home[0] == '/')
    out.emplace_back(std::filesystem::path(xdg_config_home) / "tsmh" / "link.key");
  else if (home != nullptr && home[0] != '\0')
    out.emplace_back(std::filesystem::path(home) / ".config" / "tsmh" / "link.key");
  out.emplace_back("/etc/tsmh/link.key");
  return out;
}

std::optional<std::filesystem::path> find_key_file(std::string_view flag, const char* env,
                                                   const char* xdg_config_home, const char* home) {
  auto must_exist = [](std::filesystem::path p, std::string_view source) {
    std::error_code ec;
    if (!std::filesystem::exists(p, ec))
      throw LinkKeyError("link key " + p.string() + " (from " + std::string(source) +
                         ") does not exist; create it with `tsm-link keygen --output " + p.string() +
                         "`");
    return p;
  };
  if (!flag.empty()) return must_exist(std::filesystem::path(flag), "--key");
  if (env != nullptr && env[0] != '\0') return must_exist(env, kLinkKeyEnv);
  for (const auto& p : default_key_locations(xdg_config_home, home)) {
    std::error_code ec;
    if (std::filesystem::exists(p, ec)) return p;
  }
  return std::nullopt;
}

bool is_host_local_url(std::string_view url) {
  const lcmtypes::LcmUrl parsed = lcmtypes::parse_lcm_url(url);
  return parsed.provider == lcmtypes::LcmProvider::kMemq ||
         parsed.provider == lcmtypes::LcmProvider::kFile || parsed.host_only();
}

LinkSecurity resolve_link_security(std::string_view url, const LinkSecurityOptions& options) {
  // A URL LCM could read two ways is an error with or without a key.
  lcmtypes::parse_lcm_url(url);
  const auto file = find_key_file(options.key_file, std::getenv(kLinkKeyEnv),
                                  std::getenv("XDG_CONFIG_HOME"), std::getenv("HOME"));
  LinkSecurity s;
  if (file) {
    auto key = std::make_shared<const LinkKey>(LinkKey::load(*file));
    s.notice = "LCM link authenticated with key " + file->string() + " (fingerprint " +
               key->fingerprint() + ")";
    s.key = std::move(key);
    return s;
  }
  if (is_host_local_url(url)) {
    s.notice = "LCM link NOT authenticated (no link key found): allowed only because '" +
               std::string(url) +
               "' is confined to this host (any local process can still command it; create a "
               "key with `tsm-link keygen` to authenticate)";
    return s;
  }
  std::string looked = "--key, $" + std::string(kLinkKeyEnv);
  for (const auto& p : default_key_locations(std::getenv("XDG_CONFIG_HOME"), std::getenv("HOME")))
    looked += ", " + p.string();
  if (options.insecure) {
    s.notice = "WARNING: --insecure: LCM link NOT authenticated; any host that can reach '" +
               std::string(url) + "' can command motion and force (looked for a key in: " + looked +
               ")";
    return s;
  }
  throw LinkKeyError(
      "no LCM link key found (looked in: " + looked + ") and '" + std::string(url) +
      "' is reachable from other hosts (only udpm with ttl=0, memq:// and file:// stay on "
      "this host). Create a key once with `tsm-link keygen` and give every peer a copy (mode 0600), "
      "or on an isolated network pass --insecure");
}

}  // namespace tsmh::bridge
