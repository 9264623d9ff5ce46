#include "bridge/host_only.hpp"

#include <dirent.h>
#include <linux/filter.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <charconv>
#include <cstdlib>
#include <string>

namespace tsmh::bridge {

std::optional<int> host_only_udpm_port(std::string_view url) {
  constexpr std::string_view scheme = "udpm://";
  if (url.substr(0, scheme.size()) != scheme) return std::nullopt;
  const std::string_view rest = url.substr(scheme.size());
  const auto query = rest.find('?');
  const std::string_view address = rest.substr(0, query);
  const auto colon = address.rfind(':');
  if (colon == std::string_view::npos || query == std::string_view::npos) return std::nullopt;
  int port = 0;
  const std::string_view digits = address.substr(colon + 1);
  const auto [end, ec] = std::from_chars(digits.data(), digits.data() + digits.size(), port);
  if (ec != std::errc{} || end != digits.data() + digits.size() || port <= 0 || port > 65535)
    return std::nullopt;
  // Options: key=value joined by '&'; only an explicit ttl=0 counts.
  std::string_view options = rest.substr(query + 1);
  while (!options.empty()) {
    const auto amp = options.find('&');
    const std::string_view option = options.substr(0, amp);
    if (option == "ttl=0") return port;
    if (amp == std::string_view::npos) break;
    options.remove_prefix(amp + 1);
  }
  return std::nullopt;
}

int restrict_udp_port_to_host(int port) noexcept {
  const unsigned lo = if_nametoindex("lo");
  if (lo == 0) return 0;
  // Accept (return the whole datagram) when the kernel looped it back from
  // this host's own multicast, or when it arrived on the loopback interface
  // (multicast routed via lo, unicast to 127.0.0.1 or to this host's own
  // addresses); drop everything that came in on another interface.
  sock_filter code[] = {
      BPF_STMT(BPF_LD | BPF_B | BPF_ABS, static_cast<__u32>(SKF_AD_OFF + SKF_AD_PKTTYPE)),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, PACKET_LOOPBACK, 3, 0),
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, static_cast<__u32>(SKF_AD_OFF + SKF_AD_IFINDEX)),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, lo, 1, 0),
      BPF_STMT(BPF_RET | BPF_K, 0),
      BPF_STMT(BPF_RET | BPF_K, 0xFFFFFFFF),
  };
  const sock_fprog program{static_cast<unsigned short>(sizeof code / sizeof code[0]), code};
  // LCM keeps its socket to itself: find it among this process's descriptors.
  DIR* dir = opendir("/proc/self/fd");
  if (dir == nullptr) return 0;
  int filtered = 0;
  while (const dirent* entry = readdir(dir)) {
    const int fd = std::atoi(entry->d_name);
    if (fd <= 2 || fd == dirfd(dir)) continue;
    int type = 0;
    socklen_t type_len = sizeof type;
    if (getsockopt(fd, SOL_SOCKET, SO_TYPE, &type, &type_len) != 0 || type != SOCK_DGRAM) continue;
    sockaddr_in address{};
    socklen_t address_len = sizeof address;
    if (getsockname(fd, reinterpret_cast<sockaddr*>(&address), &address_len) != 0 ||
        address.sin_family != AF_INET || ntohs(address.sin_port) != port)
      continue;
    if (setsockopt(fd, SOL_SOCKET, SO_ATTACH_FILTER, &program, sizeof program) == 0) ++filtered;
  }
  closedir(dir);
  return filtered;
}

}  // namespace tsmh::bridge
