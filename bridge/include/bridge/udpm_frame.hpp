#pragma once
// One LCM message as the udpm provider puts it on the wire, built by hand so
// that a prepared datagram can be sent with a single sendto() where LCM's
// own publish() may not run (a signal handler: bridge/crash_stop.hpp).
//
// LCM 1.3.1 (lcm/lcm_udpm.c, lcm_udpm_publish) sends a message whose
// channel name, NUL and payload fit in one datagram as a "short" message:
//
//   offset 0  u32 magic 0x4c433032 ("LC02"), big-endian
//          4  u32 sequence number of the sender's LCM instance, big-endian
//          8  channel name, then one NUL byte
//          .. payload (the encoded message and, on a keyed link, its trailer)
//
// to the group and port of the udpm URL, with the URL's multicast TTL
// (default 0) and multicast loopback on. Receivers do not check the
// sequence number of short messages (only fragments of long ones use it).

#include <netinet/in.h>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace tsmh::bridge {

/// Where a udpm URL's messages go.
struct UdpmEndpoint {
  sockaddr_in group{};  ///< multicast address and port, network byte order
  int ttl = 0;          ///< the URL's ttl option; LCM's default is 0
};

/// The endpoint of a "udpm://ADDR:PORT?opt=v&..." URL (ADDR:PORT omitted:
/// LCM's 239.255.76.67:7667); nullopt for any other provider or a URL LCM
/// would not accept (a bad address or port, a non-numeric ttl).
std::optional<UdpmEndpoint> udpm_endpoint(std::string_view url);

inline constexpr std::uint32_t kUdpmShortMagic = 0x4c433032;  // "LC02"
inline constexpr std::size_t kUdpmShortHeaderBytes = 8;
inline constexpr std::size_t kLcmMaxChannelBytes = 63;  // LCM_MAX_CHANNEL_NAME_LENGTH

/// Writes the datagram of one short message into out[0..capacity): header,
/// channel, NUL, payload. Returns its size, or 0 when the channel is empty or
/// longer than LCM allows, or the datagram does not fit. No allocation.
std::size_t frame_udpm_short(std::string_view channel, std::uint32_t lcm_seqno,
                             const std::uint8_t* payload, std::size_t size, std::uint8_t* out,
                             std::size_t capacity) noexcept;

}  // namespace tsmh::bridge
