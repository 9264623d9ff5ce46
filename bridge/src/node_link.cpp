#include "bridge/node_link.hpp"

#include <cstdio>

#include "bridge/host_only.hpp"
#include "bridge/lcm_url.hpp"

namespace tsmh::bridge {

namespace {

// The URL and the key, or the exit status 2 after saying why not.
int resolve_security(const char* program, const NodeLinkOptions& options, std::string& url,
                     LinkSecurity& security) {
  try {
    url = resolve_lcm_url(options.url);
    security = resolve_link_security(url, options.security);
  } catch (const LinkKeyError& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return 2;
  } catch (const LcmUrlError& e) {
    std::fprintf(stderr, "%s: error: %s\n", program, e.what());
    return 2;
  }
  std::fprintf(stderr, "%s: %s\n", program, security.notice.c_str());
  return 0;
}

}  // namespace

int resolve_node_link(const char* program, const NodeLinkOptions& options, BridgeConfig& out) {
  LinkSecurity security;
  if (const int status = resolve_security(program, options, out.url, security)) return status;
  out.prefix = options.prefix;
  out.key = security.key;
  return 0;
}

int start_node_link(const char* program, const NodeLinkOptions& options, NodeLink& out) {
  std::string resolved;
  if (const int status = resolve_security(program, options, resolved, out.security)) return status;
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

void print_session_fault(const char* program, const char* peer, const SessionFault& fault,
                         const char* consequence) {
  std::fprintf(stderr,
               "%s: FAULT: another %s session on the link (sender %016llx naming %016llx: a "
               "second keyed %s, a restarted one or a replay)%s\n",
               program, peer, static_cast<unsigned long long>(fault.sender_id),
               static_cast<unsigned long long>(fault.names), peer, consequence);
}

}  // namespace tsmh::bridge
