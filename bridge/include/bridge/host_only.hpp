#pragma once
// Receiving from this host only, for udpm URLs with ttl=0 (the default).
//
// TTL 0 keeps what we send on this host, but LCM 1.3's udpm socket is bound
// to 0.0.0.0:port and joins the group on the default interface, so any host
// that reaches the port is heard (unicast datagrams to the external address
// are accepted). LCM has no option to bind it to an
// interface; we attach a classic BPF socket filter (SO_ATTACH_FILTER, no
// privilege needed) to LCM's receive socket that keeps only datagrams that
// came in on the loopback interface or were looped back by this host's own
// multicast (packet type PACKET_LOOPBACK), and drops the rest in the kernel.

#include <optional>
#include <string_view>

namespace tsmh::bridge {

/// The port of a udpm URL whose options say ttl=0 ("udpm://239.255.76.67:7667?ttl=0&...");
/// nullopt for any other URL (another provider, another TTL, no explicit ttl).
/// The URL is read by the strict parser (lcmtypes/lcm_url.hpp): one that
/// LCM could read otherwise ("?ttl=0&ttl=1" sends with TTL 1) throws LcmUrlError.
std::optional<int> host_only_udpm_port(std::string_view url);

/// Attaches the host-only filter to every IPv4 UDP socket of this process
/// bound to `port` (LCM's receive sockets for that URL: call after LCM has
/// created them, i.e. after subscribe() and getFileno()). Returns how many
/// sockets were filtered; 0 means none was found or the kernel refused.
int restrict_udp_port_to_host(int port) noexcept;

}  // namespace tsmh::bridge
