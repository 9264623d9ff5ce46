#include "lcmtypes/lcm_url.hpp"

#include <arpa/inet.h>

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <vector>

#include "realtime/enum_names.hpp"

namespace tsmh::lcmtypes {
namespace {

// LCM's own default network for udpm and mpudpm (lcm_udpm.c).
constexpr std::string_view kDefaultGroup = "239.255.76.67";
constexpr int kDefaultPort = 7667;

class Parser {
 public:
  explicit Parser(std::string_view url) : url_(url) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw LcmUrlError("LCM URL '" + std::string(url_) + "': " + what);
  }
  [[noreturn]] void fail_option(std::string_view key, const std::string& what) const {
    fail("option '" + std::string(key) + "' " + what);
  }

  // Decimal digits only, no sign, no leading zero (LCM reads "010" as 8),
  // within [lo, hi].
  std::int64_t whole(std::string_view key, std::string_view value, std::int64_t lo,
                     std::int64_t hi) const {
    const std::string range = std::to_string(lo) + ".." + std::to_string(hi);
    bool digits = !value.empty() && value.size() <= 19 && (value.size() == 1 || value[0] != '0');
    for (char c : value)
      digits = digits && c >= '0' && c <= '9';
    if (!digits)
      fail_option(key, "= '" + std::string(value) + "' is not a decimal whole number " + range +
                           " (no sign, no leading zero)");
    std::int64_t v = 0;
    const auto [end, ec] = std::from_chars(value.data(), value.data() + value.size(), v);
    if (ec != std::errc{} || end != value.data() + value.size() || v < lo || v > hi)
      fail_option(key, "= " + std::string(value) + " is outside " + range);
    return v;
  }

  int port(std::string_view text) const {
    bool digits = !text.empty() && text.size() <= 5 && text[0] != '0';
    for (char c : text)
      digits = digits && c >= '0' && c <= '9';
    const long v = digits ? std::strtol(std::string(text).c_str(), nullptr, 10) : 0;
    if (!digits || v < 1 || v > 65535)
      fail("port '" + std::string(text) + "' is not a decimal number 1..65535");
    return static_cast<int>(v);
  }

  // "GROUP:PORT" (udpm, mpudpm: an IPv4 multicast group) or "HOST:PORT" (tcpq).
  void network(std::string_view net, bool multicast, LcmUrl& out) const {
    const auto colon = net.rfind(':');
    if (colon == std::string_view::npos)
      fail("address '" + std::string(net) + "' has no port (" +
           std::string(provider_name(out.provider)) + "://" +
           (multicast ? "GROUP:PORT" : "HOST:PORT") + ")");
    out.address = std::string(net.substr(0, colon));
    out.port = port(net.substr(colon + 1));
    if (multicast) {
      in_addr a{};
      if (inet_pton(AF_INET, out.address.c_str(), &a) != 1)
        fail("group '" + out.address + "' is not an IPv4 address (a.b.c.d)");
      if (!IN_MULTICAST(ntohl(a.s_addr)))
        fail("group '" + out.address + "' is not a multicast address (224.0.0.0-239.255.255.255)");
    } else {
      bool ok = !out.address.empty();
      for (char c : out.address)
        ok = ok && ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '-');
      if (!ok) fail("host '" + out.address + "' is not a host name or IPv4 address");
    }
  }

 private:
  std::string_view url_;
};

struct Option {
  std::string_view key;
  std::string_view value;
};

}  // namespace

std::string_view provider_name(LcmProvider provider) noexcept {
  return realtime::enum_name<LcmProvider::kFile>(
      provider, {"udpm", "mpudpm", "tcpq", "memq", "file"}, "unknown");
}

bool LcmUrl::host_only() const noexcept {
  return provider == LcmProvider::kUdpm && ttl == 0;
}

LcmUrl parse_lcm_url(std::string_view url) {
  const Parser p(url);
  LcmUrl out;
  out.text = std::string(url);
  const auto sep = url.find("://");
  if (url.empty()) p.fail("empty");
  if (sep == std::string_view::npos) p.fail("no provider (provider://..., e.g. udpm://)");
  const std::string_view scheme = url.substr(0, sep);
  if (scheme == "udpm")
    out.provider = LcmProvider::kUdpm;
  else if (scheme == "mpudpm")
    out.provider = LcmProvider::kMpudpm;
  else if (scheme == "tcpq")
    out.provider = LcmProvider::kTcpq;
  else if (scheme == "memq")
    out.provider = LcmProvider::kMemq;
  else if (scheme == "file")
    out.provider = LcmProvider::kFile;
  else
    p.fail("unknown provider '" + std::string(scheme) + "' (udpm, mpudpm, tcpq, memq, file)");

  std::string_view rest = url.substr(sep + 3);
  const auto query = rest.find('?');
  const std::string_view net = rest.substr(0, query);
  std::vector<Option> options;
  if (query != std::string_view::npos) {
    std::string_view text = rest.substr(query + 1);
    if (text.find('?') != std::string_view::npos)
      p.fail("more than one '?' (options are joined with '&')");
    while (true) {
      const auto amp = text.find('&');
      const std::string_view item = text.substr(0, amp);
      const auto eq = item.find('=');
      if (item.empty()) p.fail("empty option (a '&' or '?' with nothing after it)");
      if (eq == 0) p.fail("option '" + std::string(item) + "' has no name");
      if (eq == std::string_view::npos || eq + 1 == item.size())
        p.fail_option(item.substr(0, eq), "has no value (name=value)");
      const Option o{item.substr(0, eq), item.substr(eq + 1)};
      if (o.value.find('=') != std::string_view::npos)
        p.fail_option(o.key, "= '" + std::string(o.value) + "' contains '='");
      for (const auto& seen : options)
        if (seen.key == o.key)
          p.fail_option(o.key, "is given twice ('" + std::string(seen.value) + "', then '" +
                                   std::string(o.value) +
                                   "'; LCM would silently use the last one)");
      options.push_back(o);
      if (amp == std::string_view::npos) break;
      text.remove_prefix(amp + 1);
    }
  }

  auto unknown = [&](const Option& o, std::string_view known) {
    p.fail_option(o.key, "is unknown to " + std::string(scheme) + " (" + std::string(known) + ")");
  };
  switch (out.provider) {
    case LcmProvider::kUdpm:
    case LcmProvider::kMpudpm: {
      const bool mp = out.provider == LcmProvider::kMpudpm;
      if (net.empty()) {
        out.address = std::string(kDefaultGroup);
        out.port = kDefaultPort;
      } else {
        p.network(net, true, out);
      }
      for (const auto& o : options) {
        if (o.key == "ttl")
          out.ttl = static_cast<int>(p.whole(o.key, o.value, 0, 255));
        else if (o.key == "recv_buf_size")
          out.recv_buf_size =
              static_cast<int>(p.whole(o.key, o.value, 1, std::numeric_limits<int>::max()));
        else if (mp && o.key == "nports")
          out.nports = static_cast<int>(p.whole(o.key, o.value, 1, 65536 - out.port));
        else
          unknown(o, mp ? "ttl, recv_buf_size, nports" : "ttl, recv_buf_size");
      }
      break;
    }
    case LcmProvider::kTcpq:
      if (net.empty()) {
        out.address = "127.0.0.1";  // LCM's default hub
        out.port = 7700;
      } else {
        p.network(net, false, out);
      }
      for (const auto& o : options)
        unknown(o, "it takes no options");
      break;
    case LcmProvider::kMemq:
      if (!net.empty()) p.fail("memq takes no address (memq://)");
      for (const auto& o : options)
        unknown(o, "it takes no options");
      break;
    case LcmProvider::kFile:
      if (net.empty()) p.fail("no file name (file:///path/to/log.lcmlog)");
      out.address = std::string(net);
      for (const auto& o : options) {
        if (o.key == "mode") {
          if (o.value != "r" && o.value != "w" && o.value != "a")
            p.fail_option(o.key, "= '" + std::string(o.value) + "' is not r, w or a");
          out.mode = o.value[0];
        } else if (o.key == "speed") {
          char* end = nullptr;
          const std::string text(o.value);
          const double v = std::strtod(text.c_str(), &end);
          if (end != text.c_str() + text.size() || !std::isfinite(v) || v < 0 ||
              text.find_first_not_of("0123456789.") != std::string::npos)
            p.fail_option(o.key, "= '" + text + "' is not a finite decimal number >= 0");
          out.speed = v;
        } else if (o.key == "start_timestamp") {
          out.start_timestamp =
              p.whole(o.key, o.value, 0, std::numeric_limits<std::int64_t>::max());
        } else {
          unknown(o, "mode, speed, start_timestamp");
        }
      }
      if (out.mode && *out.mode != 'r') {
        if (out.speed)
          p.fail_option("speed", std::string("applies to reading a log, not to mode=") + *out.mode);
        if (out.start_timestamp)
          p.fail_option("start_timestamp",
                        std::string("applies to reading a log, not to mode=") + *out.mode);
      }
      break;
  }
  return out;
}

}  // namespace tsmh::lcmtypes
