#pragma once
// The start-up of a standalone LCM node that speaks our messages with
// lcm-gen's types (external-master-adapter, slave-node-skeleton): its
// --lcm-url/--prefix/--key/--insecure options, the link key (or the refusal
// to run unkeyed on a network URL), the signer/verifier/session that go with
// a key, and LCM itself, confined to this host for a ttl=0 URL. A node built
// on the bridge's Receiver/Sender (virtual-slave) takes the same options and
// resolves them with resolve_node_link() into its BridgeConfig. Then the
// node's period (NodeTicker): the project's pacing, LCM drained, the session
// ticked, until a stop signal or the end of --duration.

#include <signal.h>

#include <cstdint>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <vector>

#include "bridge/lcm_url.hpp"
#include "bridge/link_auth.hpp"
#include "bridge/link_security.hpp"
#include "bridge/link_session.hpp"
#include "realtime/pacing.hpp"

namespace tsmh::bridge {

/// What the options hold.
struct NodeLinkOptions {
  std::string url;               ///< --lcm-url; empty: $LCM_DEFAULT_URL, then LCM's default
  std::string prefix;            ///< --prefix: per-arm channel prefix
  LinkSecurityOptions security;  ///< --key, --insecure
};

/// Adds --lcm-url, the prefix option (`prefix_names`, e.g. "--prefix"), --key
/// and --insecure to a CLI11 app. A template so that the bridge needs no
/// CLI11; only the programs that call it include <CLI/CLI.hpp>.
/// `insecure_help` says what an unkeyed peer could do to this node.
template <class App>
void add_node_link_options(App& app, NodeLinkOptions& o, const char* prefix_names,
                           const char* prefix_help, const char* insecure_help) {
  app.add_option("--lcm-url", o.url, "LCM URL (default: $LCM_DEFAULT_URL, then LCM's default)");
  app.add_option(prefix_names, o.prefix, prefix_help);
  app.add_option("--key", o.security.key_file, kKeyOptionHelp);
  app.add_flag("--insecure", o.security.insecure, insecure_help);
}

/// A started node's link. signer, verifier and session are null when the
/// link is unauthenticated (no key on a host-local URL, or --insecure).
struct NodeLink {
  LinkSecurity security;
  std::unique_ptr<MessageSigner> signer;
  std::unique_ptr<MessageVerifier> verifier;
  /// One peer session at a time, re-armed after the peer's goodbye or its
  /// silence (a node serves the next server or master).
  std::unique_ptr<LinkSession> session;
  std::unique_ptr<lcm::LCM> lcm;
};

/// The URL (resolve_lcm_url: empty is $LCM_DEFAULT_URL, then the default),
/// the prefix and the link key for a node on the bridge's Receiver/Sender,
/// printing "<program>: <notice>" to stderr. Returns 0 with `out` filled, or
/// 2 after printing "<program>: error: ..." for a bad URL or key (also no key
/// on a network URL without --insecure).
int resolve_node_link(const char* program, const NodeLinkOptions& options, BridgeConfig& out);

/// Resolves the link security (printing "<program>: <notice>" to stderr),
/// creates LCM and, for a ttl=0 udpm URL, confines its receive socket to
/// this host. Returns 0 with `out` filled, or the exit status after printing
/// "<program>: error: ..." or the LCM failure: 2 for a bad URL or key (also
/// no key on a network URL without --insecure), 1 when LCM cannot start or
/// its socket cannot be confined.
int start_node_link(const char* program, const NodeLinkOptions& options, NodeLink& out);

/// Prints "<program>: FAULT: another <peer> session on the link (sender X
/// naming Y: ...)<consequence>" to stderr: the one report of a session ended
/// by a second key holder, the same words in every node.
void print_session_fault(const char* program, const char* peer, const SessionFault& fault,
                         const char* consequence);

/// A standalone node's end after a session FAULT: print_session_fault() with
/// "; <action>, exit 4 (<N> such <messages>)", N the keyed messages of the
/// other session its inbox counted; returns 4, the nodes' exit status for it.
int session_fault_exit(const char* program, const char* peer, const SessionFault& fault,
                       const char* action, std::int64_t other_session, const char* messages);

/// The periods of a standalone node's loop: absolute deadlines on the
/// project's pacing (realtime::Pacer: after an overrun the schedule re-bases
/// on the next deadline ahead instead of running late periods back to back);
/// each period first drains what LCM received, without blocking, and ticks
/// the session (a silent peer ends it after its timeout). Stopping is polled,
/// not signalled: the loop ends at its next period after a stop signal or
/// at the end of the duration, so it always leaves through the caller's
/// safe exit (zero torque, hold).
///   NodeTicker ticker(node, rate_hz, duration_s, stop_signals);
///   while (!session_over && ticker.next()) { ... the period at ticker.now_ns() ... }
class NodeTicker {
 public:
  /// `rate_hz` > 0; `duration_s` <= 0: until a stop signal; `stop_signals`:
  /// what block_terminating_signals() returned before LCM started. The
  /// first period is due one period from now.
  NodeTicker(NodeLink& link, double rate_hz, double duration_s, const sigset_t& stop_signals);

  /// false, without waiting, once a signal of the stop set is pending or the
  /// duration is over; otherwise sleeps to the next deadline, drains LCM,
  /// ticks the session and returns true.
  bool next();
  /// CLOCK_MONOTONIC when the last next() had drained LCM, ns.
  std::int64_t now_ns() const noexcept { return now_; }
  std::int64_t period_ns() const noexcept { return pace_.period_ns(); }

 private:
  NodeLink& link_;
  sigset_t stop_signals_;
  double duration_s_;
  std::int64_t start_ns_;
  realtime::Pacer pace_;
  bool ticked_ = false;
  std::int64_t now_ = 0;
};

/// Sends one of our messages (lcm-gen's type) on `channel`: encoded, signed
/// with the link's key when it has one, published. `bytes` is the caller's
/// buffer, kept between calls so that only the first call allocates.
template <class Message>
void publish_message(NodeLink& link, const std::string& channel, const Message& msg,
                     std::vector<std::uint8_t>& bytes) {
  const int size = msg.getEncodedSize();
  const std::size_t trailer = link.signer ? kAuthTrailerBytes : 0;
  bytes.resize(static_cast<std::size_t>(size) + trailer);
  msg.encode(bytes.data(), 0, size);
  if (link.signer)
    link.signer->sign(channel, bytes.data(), static_cast<std::size_t>(size), bytes.data() + size);
  link.lcm->publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
}

}  // namespace tsmh::bridge
