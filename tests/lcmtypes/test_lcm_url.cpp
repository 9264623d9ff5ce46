// lcmtypes::parse_lcm_url: one reading of every LCM URL, and an error naming
// the URL and the option wherever LCM would guess.
#include <gtest/gtest.h>

#include <string>

#include "lcmtypes/lcm_url.hpp"

namespace tsmh::lcmtypes {
namespace {

// The error's text, or "ok".
std::string error_of(const std::string& url) {
  try {
    parse_lcm_url(url);
    return "ok";
  } catch (const LcmUrlError& e) {
    return e.what();
  }
}

void expect_error(const std::string& url, const std::string& part) {
  const std::string e = error_of(url);
  EXPECT_NE(e, "ok") << url;
  EXPECT_NE(e.find("'" + url + "'"), std::string::npos) << "names the URL: " << e;
  EXPECT_NE(e.find(part), std::string::npos) << "says '" << part << "': " << e;
}

TEST(LcmUrl, ReadsTheProjectsUrls) {
  const LcmUrl u = parse_lcm_url("udpm://239.255.76.67:7731?ttl=0&recv_buf_size=2097152");
  EXPECT_EQ(u.provider, LcmProvider::kUdpm);
  EXPECT_EQ(u.address, "239.255.76.67");
  EXPECT_EQ(u.port, 7731);
  EXPECT_EQ(u.ttl, 0);
  EXPECT_EQ(u.recv_buf_size, 2097152);
  EXPECT_TRUE(u.host_only());

  EXPECT_FALSE(parse_lcm_url("udpm://239.255.76.67:7667?ttl=1").host_only());
  EXPECT_FALSE(parse_lcm_url("udpm://239.255.76.67:7667").host_only()) << "ttl must be said";
  const LcmUrl d = parse_lcm_url("udpm://?ttl=0");  // LCM's default group and port
  EXPECT_EQ(d.address, "239.255.76.67");
  EXPECT_EQ(d.port, 7667);
  EXPECT_TRUE(d.host_only());
  EXPECT_EQ(parse_lcm_url("memq://").provider, LcmProvider::kMemq);
  const LcmUrl f = parse_lcm_url("file:///tmp/run.lcmlog?mode=w");
  EXPECT_EQ(f.provider, LcmProvider::kFile);
  EXPECT_EQ(f.address, "/tmp/run.lcmlog");
  EXPECT_EQ(f.mode, 'w');
  EXPECT_FALSE(f.host_only());
  EXPECT_EQ(parse_lcm_url("file:///tmp/run.lcmlog?speed=0.5&start_timestamp=10").speed, 0.5);
  EXPECT_EQ(parse_lcm_url("tcpq://localhost:7700").port, 7700);
  EXPECT_EQ(parse_lcm_url("mpudpm://239.255.76.67:7667?nports=8&ttl=0").nports, 8);
  EXPECT_FALSE(parse_lcm_url("mpudpm://239.255.76.67:7667?ttl=0").host_only())
      << "only udpm's one port can be confined";
}

// LCM 1.3 keeps the last of a repeated option: this URL sends with TTL 1,
// and was once taken as confined to this host (no key needed).
TEST(LcmUrl, ARepeatedOptionIsAnErrorNamingIt) {
  expect_error("udpm://239.255.76.67:7667?ttl=0&ttl=1",
               "option 'ttl' is given twice ('0', then '1'");
  expect_error("udpm://239.255.76.67:7667?ttl=0&ttl=0", "option 'ttl' is given twice");
  expect_error("udpm://239.255.76.67:7667?ttl=0?ttl=1", "more than one '?'");
  expect_error("file:///x.lcmlog?mode=r&mode=w", "option 'mode' is given twice");
}

TEST(LcmUrl, AContradictionIsAnError) {
  expect_error("file:///x.lcmlog?mode=w&speed=2", "option 'speed' applies to reading a log");
  expect_error("file:///x.lcmlog?start_timestamp=5&mode=a", "option 'start_timestamp' applies");
}

TEST(LcmUrl, AnUnknownOptionIsAnError) {
  expect_error("udpm://239.255.76.67:7667?ttl=0&tll=1", "option 'tll' is unknown to udpm");
  expect_error("udpm://239.255.76.67:7667?transmit_only=1", "option 'transmit_only' is unknown");
  expect_error("udpm://239.255.76.67:7667?nports=2", "option 'nports' is unknown to udpm");
  expect_error("memq://?ttl=0", "option 'ttl' is unknown to memq");
  expect_error("tcpq://localhost:7700?ttl=0", "option 'ttl' is unknown to tcpq");
}

TEST(LcmUrl, ABadNumberIsAnErrorNamingTheOption) {
  expect_error("udpm://239.255.76.67:7667?ttl=01", "option 'ttl' = '01' is not a decimal");
  expect_error("udpm://239.255.76.67:7667?ttl=0x0", "option 'ttl' = '0x0'");
  expect_error("udpm://239.255.76.67:7667?ttl=256", "option 'ttl' = 256 is outside 0..255");
  expect_error("udpm://239.255.76.67:7667?ttl=-1", "option 'ttl' = '-1'");
  expect_error("udpm://239.255.76.67:7667?ttl= 0", "option 'ttl' = ' 0'");
  expect_error("udpm://239.255.76.67:7667?ttl=", "option 'ttl' has no value");
  expect_error("udpm://239.255.76.67:7667?ttl", "option 'ttl' has no value");
  expect_error("udpm://239.255.76.67:7667?recv_buf_size=0", "option 'recv_buf_size' = 0");
  expect_error("udpm://239.255.76.67:7667?recv_buf_size=99999999999",
               "option 'recv_buf_size' = 99999999999 is outside");
  expect_error("file:///x.lcmlog?speed=nan", "option 'speed' = 'nan'");
  expect_error("file:///x.lcmlog?speed=1e400", "option 'speed'");
  expect_error("file:///x.lcmlog?start_timestamp=99999999999999999999", "option 'start_timestamp'");
  expect_error("udpm://239.255.76.67:7667?ttl=0&", "empty option");
  expect_error("udpm://239.255.76.67:7667?=0", "has no name");
}

TEST(LcmUrl, ABadAddressOrProviderIsAnError) {
  expect_error("", "empty");
  expect_error("239.255.76.67:7667", "no provider");
  expect_error("udp://239.255.76.67:7667", "unknown provider 'udp'");
  expect_error("udpm://239.255.76.67?ttl=0", "has no port");
  expect_error("udpm://239.255.76.67:0?ttl=0", "port '0'");
  expect_error("udpm://239.255.76.67:65536?ttl=0", "port '65536'");
  expect_error("udpm://239.255.76.67:07667?ttl=0", "port '07667'");
  expect_error("udpm://239.255.76.67:0x1df3?ttl=0", "port '0x1df3'");
  expect_error("udpm://10.0.0.1:7667?ttl=0", "not a multicast address");
  expect_error("udpm://239.255.76:7667?ttl=0", "not an IPv4 address");
  expect_error("memq://x", "memq takes no address");
  expect_error("file://", "no file name");
}

}  // namespace
}  // namespace tsmh::lcmtypes
