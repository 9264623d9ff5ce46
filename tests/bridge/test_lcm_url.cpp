#include <gtest/gtest.h>

#include "bridge/lcm_url.hpp"
#include "process.hpp"
#include "test_support.hpp"

namespace tsmh::bridge {
namespace {

TEST(LcmUrl, CommandLineThenEnvironmentThenDefault) {
  EXPECT_EQ(resolve_lcm_url("memq://", "udpm://1.2.3.4:5?ttl=0"), "memq://");
  EXPECT_EQ(resolve_lcm_url("", "udpm://239.1.1.1:7000?ttl=0"), "udpm://239.1.1.1:7000?ttl=0");
  EXPECT_EQ(resolve_lcm_url("", ""), "udpm://239.255.76.67:7667?ttl=0");
  EXPECT_EQ(resolve_lcm_url("", nullptr), std::string(kDefaultLcmUrl));
}

TEST(LcmUrl, BadProviderIsAClearError) {
  try {
    open_lcm("nosuchprovider://x");
    FAIL() << "expected LcmUrlError";
  } catch (const LcmUrlError& e) {
    EXPECT_NE(std::string(e.what()).find("nosuchprovider://x"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("unknown provider"), std::string::npos) << e.what();
  }
}

// Every URL a program resolves goes through the strict parser, from the
// command line or from $LCM_DEFAULT_URL (named in the error).
TEST(LcmUrl, ResolvedUrlsAreReadStrictly) {
  EXPECT_THROW(resolve_lcm_url("udpm://239.255.76.67:7667?ttl=0&ttl=1", nullptr), LcmUrlError);
  try {
    resolve_lcm_url("", "udpm://239.255.76.67:7667?ttl=0&ttl=1");
    FAIL() << "expected LcmUrlError";
  } catch (const LcmUrlError& e) {
    EXPECT_NE(std::string(e.what()).find("$LCM_DEFAULT_URL: LCM URL "
                                         "'udpm://239.255.76.67:7667?ttl=0&ttl=1': option 'ttl' "
                                         "is given twice"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(open_lcm("udpm://239.255.76.67:7667?ttl=0&ttl=1"), LcmUrlError);
}

// In a fresh network namespace only a downed loopback exists, so LCM's
// multicast self-test fails as on a machine without a network. The error must
// carry the fix, and the fix must work (applied inside that namespace only).
TEST(LcmUrl, NoMulticastRouteErrorSaysHowToFixIt) {
  const std::string url = "udpm://239.255.76.67:7667?ttl=0";
  const auto broken = test::run({TSMH_BRIDGE_PEER, "open", url}, /*new_netns=*/true);
  if (broken.exit_code == test::kNoNamespace)
    GTEST_SKIP() << "cannot unshare a network namespace (needs root)";
  EXPECT_EQ(broken.exit_code, 3) << broken.output;
  EXPECT_NE(broken.output.find("ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo"),
            std::string::npos)
      << broken.output;

  const std::string fix = test::cat(
      "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && ",
      "exec '", TSMH_BRIDGE_PEER, "' open '", url, "'");
  const auto fixed = test::run({"sh", "-c", fix}, /*new_netns=*/true);
  EXPECT_EQ(fixed.exit_code, 0) << fixed.output;
  EXPECT_NE(fixed.output.find("opened"), std::string::npos) << fixed.output;
}

}  // namespace
}  // namespace tsmh::bridge
