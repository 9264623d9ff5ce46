#pragma once
// Which LCM network to join, and opening it with an error that says how to fix
// the usual failure (no multicast route). Every URL is read by the one strict
// parser (lcmtypes/lcm_url.hpp) before LCM sees it: a repeated, unknown or
// contradictory option or a bad number is an LcmUrlError naming the URL and
// the option, never a guess.

#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <stdexcept>
#include <string>
#include <string_view>

#include "lcmtypes/lcm_url.hpp"

namespace tsmh::bridge {

using lcmtypes::LcmUrlError;

class LinkKey;  // bridge/link_auth.hpp

/// The project's default: multicast with TTL 0, so packets never leave this
/// host (the kernel still loops them back to local subscribers).
inline constexpr std::string_view kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

/// A transport problem the user can act on; what() says what and how.
class BridgeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// `--lcm-url` when given (non-empty), else `env_value` (the LCM_DEFAULT_URL
/// environment variable, as LCM's own tools honour it) when non-empty, else
/// kDefaultLcmUrl. Throws LcmUrlError when the chosen URL does not parse
/// strictly (lcmtypes::parse_lcm_url; the variable is named when it came from it).
std::string resolve_lcm_url(std::string_view cli_url, const char* env_value);

/// Same, reading LCM_DEFAULT_URL from the environment.
std::string resolve_lcm_url(std::string_view cli_url = {});

/// Creates an LCM instance for `url`. Throws LcmUrlError when the URL does
/// not parse strictly, BridgeError when LCM cannot be created; for udpm URLs
/// the message explains the multicast self-test and the fix
/// (`ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo`).
std::unique_ptr<lcm::LCM> open_lcm(const std::string& url);

/// Where to talk: LCM URL and the per-arm channel prefix.
struct BridgeConfig {
  std::string url = std::string(kDefaultLcmUrl);
  std::string prefix{};  ///< e.g. "ARM1_"; empty for a single arm
  /// Shared link key (bridge/link_auth.hpp): a Sender signs every message, a
  /// Receiver accepts only messages signed with it (fresh, not replayed).
  /// Null: unauthenticated; a Receiver then ignores trailers it finds.
  /// Programs get it from resolve_link_security() (bridge/link_security.hpp).
  std::shared_ptr<const LinkKey> key{};
};

}  // namespace tsmh::bridge
