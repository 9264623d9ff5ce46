#pragma once
// The one parser of LCM URLs ("provider://address?option=value&..."), strict
// where LCM is lenient. LCM 1.3 keeps the last of a repeated option (so
// "udpm://...?ttl=0&ttl=1" sends with TTL 1), reads numbers with strtol base 0
// ("ttl=010" is 8) into a byte ("ttl=256" is 0), only warns about unknown
// options and takes several '?'. Whatever decides something from a URL --
// whether a link stays on this host, whether it needs the link key, which
// socket to confine -- must read it as LCM will use it; here an ambiguous
// URL is an error instead, naming the URL and the option.

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace tsmh::lcmtypes {

enum class LcmProvider : std::uint8_t {
  kUdpm,    ///< udpm://GROUP:PORT  multicast UDP
  kMpudpm,  ///< mpudpm://GROUP:PORT  multicast UDP over a range of ports
  kTcpq,    ///< tcpq://HOST:PORT  through an lcm-hub-style TCP queue
  kMemq,    ///< memq://  within one process
  kFile,    ///< file:///PATH  an LCM log
};

/// "udpm", "mpudpm", "tcpq", "memq", "file".
std::string_view provider_name(LcmProvider provider) noexcept;

/// A URL as LCM will use it.
struct LcmUrl {
  std::string text;  ///< the URL as given
  LcmProvider provider = LcmProvider::kUdpm;
  std::string address;     ///< the group (udpm, mpudpm), host (tcpq) or path (file); memq: empty
  int port = 0;            ///< udpm, mpudpm, tcpq; 0 for the others
  std::optional<int> ttl;  ///< udpm, mpudpm: multicast TTL 0..255
  std::optional<int> recv_buf_size;  ///< udpm, mpudpm: kernel receive buffer, bytes
  std::optional<int> nports;         ///< mpudpm: ports used from `port` on
  std::optional<char> mode;          ///< file: 'r', 'w' or 'a'
  std::optional<double> speed;       ///< file, reading: replay speed (0 = as fast as possible)
  std::optional<std::int64_t> start_timestamp;  ///< file, reading: first event's utime

  /// udpm with an explicit ttl=0: what LCM sends never leaves this host
  /// (receiving is confined separately: bridge/host_only.hpp). An omitted
  /// ttl is not taken as 0, although LCM 1.3 defaults to it: being
  /// host-only must be said, not assumed.
  bool host_only() const noexcept;
};

/// A URL that is not exactly one thing to LCM; what() names the URL and,
/// when it is about one, the option.
class LcmUrlError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// Parses `url`. Errors (LcmUrlError): no "provider://", an unknown
/// provider, a bad group, host or port (decimal 1..65535; udpm and mpudpm
/// without an address take LCM's 239.255.76.67:7667), more than one '?', an
/// empty option or one without a value, an option the provider does not
/// know, an option given twice (even with the same value), a bad number
/// (decimal digits only, no sign, no leading zero, within the option's
/// range), and options that contradict each other (a file written, mode=w
/// or a, with the reading options speed or start_timestamp).
LcmUrl parse_lcm_url(std::string_view url);

}  // namespace tsmh::lcmtypes
