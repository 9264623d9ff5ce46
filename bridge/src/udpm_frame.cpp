#include "bridge/udpm_frame.hpp"

#include <arpa/inet.h>

#include <charconv>
#include <cstring>
#include <string>

namespace tsmh::bridge {

std::optional<UdpmEndpoint> udpm_endpoint(std::string_view url) {
  constexpr std::string_view scheme = "udpm://";
  if (url.substr(0, scheme.size()) != scheme) return std::nullopt;
  std::string_view rest = url.substr(scheme.size());
  const auto query = rest.find('?');
  std::string_view address = rest.substr(0, query);
  std::string_view options = query == std::string_view::npos ? "" : rest.substr(query + 1);
  if (address.empty()) address = "239.255.76.67:7667";

  UdpmEndpoint e;
  e.group.sin_family = AF_INET;
  const auto colon = address.find(':');
  const std::string host(address.substr(0, colon));
  if (inet_aton(host.c_str(), &e.group.sin_addr) == 0) return std::nullopt;
  int port = 7667;
  if (colon != std::string_view::npos) {
    const std::string_view digits = address.substr(colon + 1);
    const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), port);
    if (ec != std::errc{} || end != digits.data() + digits.size() || port < 0 || port > 65535)
      return std::nullopt;
  }
  e.group.sin_port = htons(static_cast<std::uint16_t>(port));
  // As LCM reads them: key=value joined by '&'; the last ttl wins.
  while (!options.empty()) {
    const auto amp = options.find('&');
    const std::string_view option = options.substr(0, amp);
    if (option.substr(0, 4) == "ttl=") {
      const std::string_view digits = option.substr(4);
      int ttl = 0;
      const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), ttl);
      if (ec != std::errc{} || end != digits.data() + digits.size() || ttl < 0 || ttl > 255)
        return std::nullopt;
      e.ttl = ttl;
    }
    if (amp == std::string_view::npos) break;
    options.remove_prefix(amp + 1);
  }
  return e;
}

std::size_t frame_udpm_short(std::string_view channel, std::uint32_t lcm_seqno,
                             const std::uint8_t* payload, std::size_t size, std::uint8_t* out,
                             std::size_t capacity) noexcept {
  if (channel.empty() || channel.size() > kLcmMaxChannelBytes) return 0;
  const std::size_t total = kUdpmShortHeaderBytes + channel.size() + 1 + size;
  if (total > capacity) return 0;
  const std::uint32_t magic = htonl(kUdpmShortMagic);
  const std::uint32_t seqno = htonl(lcm_seqno);
  std::memcpy(out, &magic, 4);
  std::memcpy(out + 4, &seqno, 4);
  std::memcpy(out + kUdpmShortHeaderBytes, channel.data(), channel.size());
  out[kUdpmShortHeaderBytes + channel.size()] = 0;
  if (size > 0) std::memcpy(out + kUdpmShortHeaderBytes + channel.size() + 1, payload, size);
  return total;
}

}  // namespace tsmh::bridge
