// Receiving from this host only on udpm with ttl=0 (bridge/host_only.hpp):
// datagrams from another host (a network namespace joined by a veth pair
// stands in for it) are dropped by the socket filter; local traffic flows.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdio>
#include <lcm/lcm-cpp.hpp>
#include <string>

#include "bridge/host_only.hpp"
#include "bridge/lcm_url.hpp"
#include "bridge/link_security.hpp"
#include "bridge/receiver.hpp"
#include "bridge/sender.hpp"
#include "process.hpp"
#include "realtime/clock.hpp"
#include "test_support.hpp"

namespace tsmh::bridge {
namespace {

using test::make_state;
using test::wait_until;

TEST(HostOnly, OnlyUdpmWithTtlZeroIsHostOnly) {
  EXPECT_EQ(host_only_udpm_port("udpm://239.255.76.67:7667?ttl=0"), 7667);
  EXPECT_EQ(host_only_udpm_port("udpm://239.255.76.67:7731?recv_buf_size=2097152&ttl=0"), 7731);
  EXPECT_EQ(host_only_udpm_port("udpm://239.255.76.67:7667?ttl=1"), std::nullopt);
  EXPECT_EQ(host_only_udpm_port("udpm://239.255.76.67:7667"), std::nullopt) << "no explicit ttl";
  EXPECT_EQ(host_only_udpm_port("udpm://?ttl=0"), 7667) << "LCM's default group and port";
  EXPECT_EQ(host_only_udpm_port("memq://"), std::nullopt);
  // What LCM would read otherwise is an error, not "not host-only" (and never "host-only").
  EXPECT_THROW(host_only_udpm_port("udpm://239.255.76.67:7667?ttl=01"), LcmUrlError);
  EXPECT_THROW(host_only_udpm_port("udpm://239.255.76.67?ttl=0"), LcmUrlError) << "no port";
  EXPECT_THROW(host_only_udpm_port("file:///tmp/x.lcmlog?ttl=0"), LcmUrlError);
}

// LCM keeps the last of a repeated option, so this URL sends with TTL 1: it
// was taken as confined to this host, and a program ran without the link key.
TEST(HostOnly, ARepeatedTtlIsNeitherHostOnlyNorAllowedWithoutAKey) {
  for (const char* url :
       {"udpm://239.255.76.67:7667?ttl=0&ttl=1", "udpm://239.255.76.67:7667?ttl=1&ttl=0",
        "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4096&ttl=0"}) {
    SCOPED_TRACE(url);
    EXPECT_THROW(host_only_udpm_port(url), LcmUrlError);
    EXPECT_THROW(is_host_local_url(url), LcmUrlError);
    try {
      resolve_link_security(url, LinkSecurityOptions{.key_file = "", .insecure = false});
      ADD_FAILURE() << "no error";
    } catch (const LcmUrlError& e) {
      EXPECT_NE(std::string(e.what()).find("option 'ttl' is given twice"), std::string::npos)
          << e.what();
    }
    EXPECT_THROW(resolve_lcm_url(url, nullptr), LcmUrlError);
  }
}

/// A second "host": a network namespace with a veth pair, 10.88.N.1 here and
/// 10.88.N.2 there. Needs root and iproute2; skipped otherwise.
class OtherHost {
 public:
  OtherHost() {
    const int n = static_cast<int>(getpid() % 200) + 20;
    ns_ = test::cat("tsmh_rogue_", std::to_string(getpid()));
    here_ = test::cat("tr", std::to_string(getpid()), "a");
    there_ = test::cat("tr", std::to_string(getpid()), "b");
    here_ip_ = test::cat("10.88.", std::to_string(n), ".1");
    const std::string there_ip = test::cat("10.88.", std::to_string(n), ".2");
    const std::string script = test::cat(
        "set -e; ip netns add ", ns_, "; ip link add ", here_, " type veth peer name ", there_,
        "; ip link set ", there_, " netns ", ns_, "; ip addr add ", here_ip_, "/24 dev ", here_,
        "; ip link set ", here_, " up; ip netns exec ", ns_, " ip addr add ", there_ip, "/24 dev ",
        there_, "; ip netns exec ", ns_, " ip link set ", there_, " up");
    const auto r = test::run({"sh", "-c", script});
    ok_ = r.exit_code == 0;
    error_ = r.output;
  }
  ~OtherHost() {
    test::run({"sh", "-c", test::cat("ip netns del ", ns_, "; ip link del ", here_)});
  }
  OtherHost(const OtherHost&) = delete;
  OtherHost& operator=(const OtherHost&) = delete;
  bool ok() const { return ok_; }
  const std::string& error() const { return error_; }
  /// Sends `count` LCM datagrams (short-message framing) carrying `payload`
  /// on `channel` from the other host to this host's veth address and `port`.
  int send(int port, const std::string& channel, const std::vector<std::uint8_t>& payload,
           int count) const {
    std::string hex;
    char b[3];
    for (std::uint8_t x : payload) {
      std::snprintf(b, sizeof b, "%02x", x);
      hex += b;
    }
    const std::string py =
        test::cat("import socket,struct\ns=socket.socket(socket.AF_INET,socket.SOCK_DGRAM)\n",
                  "for i in range(", std::to_string(count), "):\n",
                  "  s.sendto(struct.pack('>II',0x4c433032,i)+b'", channel, "\\0'+bytes.fromhex('",
                  hex, "'),('", here_ip_, "',", std::to_string(port), "))\n");
    return test::run({"ip", "netns", "exec", ns_, "python3", "-c", py}).exit_code;
  }

 private:
  std::string ns_, here_, there_, here_ip_, error_;
  bool ok_ = false;
};

// The probe: unicast datagrams to this host's external address on the
// LCM port. A plain LCM instance hears them (what the filter is for); the
// bridge's Receiver on the same ttl=0 URL does not, and still hears this host.
TEST(HostOnly, DatagramsFromAnotherHostAreDroppedLocalOnesArrive) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root for a network namespace";
  OtherHost other;
  if (!other.ok()) GTEST_SKIP() << "cannot build a veth pair here: " << other.error();
  const int port = 7400 + static_cast<int>(getpid() % 200);
  const std::string url = test::cat("udpm://239.255.76.67:", std::to_string(port), "?ttl=0");
  const std::string prefix = test::unique_prefix();
  const std::string channel = prefix + "SLAVE_STATE";
  std::vector<std::uint8_t> payload;
  encode_sample(make_state(1, realtime::monotonic_utime()), payload);

  // Control: unfiltered LCM on the same URL hears the other host.
  {
    lcm::LCM plain(url);
    ASSERT_TRUE(plain.good());
    int heard = 0;
    plain.subscribeFunction<int*>(
        channel, [](const lcm::ReceiveBuffer*, const std::string&, int* n) { ++*n; }, &heard);
    plain.getFileno();
    ASSERT_EQ(other.send(port, channel, payload, 20), 0);
    for (int i = 0; i < 100 && heard < 20; ++i)
      plain.handleTimeout(10);
    ASSERT_EQ(heard, 20) << "the other host does not reach this one: the test proves nothing";
  }

  Receiver rx({.url = url, .prefix = prefix});
  auto& in = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  rx.start();
  EXPECT_GE(rx.host_only_sockets(), 1);
  ASSERT_EQ(other.send(port, channel, payload, 20), 0);
  Sender tx({.url = url, .prefix = prefix});
  auto& out = tx.outbox<SlaveStateSample>();
  tx.start();
  ASSERT_TRUE(out.publish(make_state(2, realtime::monotonic_utime())));
  ASSERT_TRUE(wait_until([&] { return in.stats().accepted == 1; })) << "local traffic arrives";
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(in.stats().received, 1U) << "the other host's 20 datagrams were dropped";
  SlaveStateSample s;
  ASSERT_NE(in.latest(s), 0U);
  EXPECT_EQ(s.seq, 2);
}

}  // namespace
}  // namespace tsmh::bridge
