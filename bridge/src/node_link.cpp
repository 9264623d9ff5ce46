#include "bridge/node_link.hpp"

#include <cstdio>

#include "bridge/host_only.hpp"
#include "bridge/lcm_url.hpp"

namespace tsmh::bridge {

int start_node_link(const char* program, const NodeLinkOptions& options, NodeLink& out) {
  std::string resolved;
  try {
    resolved = resolve_lcm_url(options.url);
    out.security = resolve_link_security(resolved, options.security);
  } catch (const LinkKeyError& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return 2;
  } catch (const LcmUrlError& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return 2;
  }
  std::fprintf(stderr, "%s: %s\n", program, out.security.notice.c_str());
  if (out.security.key) {
    out.signer = std::make_unique<MessageSigner>(out.security.key);
    out.verifier = std::make_unique<MessageVerifier>(out.security.key);
    out.session = std::make_unique<LinkSession>(*out.signer, SessionOptions{.rearm = true});
  }

  // The URL as given: an empty one honours LCM_DEFAULT_URL, as LCM's tools do.
  out.lcm = std::make_unique<lcm::LCM>(options.url);
  if (!out.lcm->good()) {
    std::fprintf(stderr,
                 "%s: cannot start LCM%s%s (no multicast route? ip link set lo multicast on; ip "
                 "route add 224.0.0.0/4 dev lo)\n",
                 program, options.url.empty() ? "" : " at ", options.url.c_str());
    out.lcm.reset();
    return 1;
  }
  // ttl=0 means this host: LCM's socket listens on every interface, so
  // confine it (bridge/host_only.hpp), or refuse to run.
  if (const auto port = host_only_udpm_port(resolved)) {
    out.lcm->getFileno();  // LCM creates its receive socket here at the latest
    if (restrict_udp_port_to_host(*port) == 0) {
      std::fprintf(stderr, "%s: error: cannot confine LCM's socket to this host\n", program);
      out.lcm.reset();
      return 1;
    }
  }
  return 0;
}

}  // namespace tsmh::bridge
