#include "bridge/host_only.hpp"

#include <dirent.h>
#include <linux/filter.h>
#include <linux/if_packet.h>
#include <net/if.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cstdlib>
#include <string>

#include "lcmtypes/lcm_url.hpp"

namespace tsmh::bridge {

std::optional<int> host_only_udpm_port(std::string_view url) {
  const lcmtypes::LcmUrl parsed = lcmtypes::parse_lcm_url(url);
  if (!parsed.host_only()) return std::nullopt;
  return parsed.port;
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
