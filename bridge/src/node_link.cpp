#include "bridge/node_link.hpp"

#include <cstdio>
#include <string>

#include "bridge/host_only.hpp"
#include "bridge/lcm_url.hpp"
#include "bridge/stop_signals.hpp"
#include "realtime/clock.hpp"

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

NodeTicker::NodeTicker(NodeLink& link, double rate_hz, double duration_s,
                       const sigset_t& stop_signals)
    : link_(link),
      stop_signals_(stop_signals),
      duration_s_(duration_s),
      start_ns_(realtime::monotonic_now_ns()),
      pace_(static_cast<std::int64_t>(1e9 / rate_hz),
            start_ns_ + static_cast<std::int64_t>(1e9 / rate_hz)) {}

bool NodeTicker::next() {
  if (ticked_) pace_.advance(realtime::monotonic_now_ns());
  // A signal outside the stop set may end the sleep early: check, sleep again.
  do {
    if (terminating_signal_pending(stop_signals_) ||
        (duration_s_ > 0.0 &&
         static_cast<double>(realtime::monotonic_now_ns() - start_ns_) >= duration_s_ * 1e9))
      return false;
  } while (!pace_.wait());
  ticked_ = true;
  while (link_.lcm->handleTimeout(0) > 0) {
  }
  now_ = realtime::monotonic_now_ns();
  if (link_.session) link_.session->tick(now_);
  return true;
}

void print_session_fault(const char* program, const char* peer, const SessionFault& fault,
                         const char* consequence) {
  std::fprintf(stderr,
               "%s: FAULT: another %s session on the link (sender %016llx naming %016llx: a "
               "second keyed %s, a restarted one or a replay)%s\n",
               program, peer, static_cast<unsigned long long>(fault.sender_id),
               static_cast<unsigned long long>(fault.names), peer, consequence);
}

int session_fault_exit(const char* program, const char* peer, const SessionFault& fault,
                       const char* action, std::int64_t other_session, const char* messages) {
  const std::string consequence = std::string("; ") + action + ", exit 4 (" +
                                  std::to_string(other_session) + " such " + messages + ")";
  print_session_fault(program, peer, fault, consequence.c_str());
  return 4;
}

}  // namespace tsmh::bridge
