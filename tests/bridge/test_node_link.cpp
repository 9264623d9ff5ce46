// The start-up of the standalone nodes (bridge/node_link.hpp): the refusal
// to run unkeyed on a network URL, the signer/verifier/session that come
// with a key, and the messages and exit statuses the programs print.

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include "bridge/link_auth.hpp"
#include "bridge/link_security.hpp"
#include "bridge/node_link.hpp"

namespace {

namespace fs = std::filesystem;
using tsmh::bridge::NodeLink;
using tsmh::bridge::NodeLinkOptions;
using tsmh::bridge::start_node_link;

// An environment where no key is found unless a test names one: ctest sets
// TSMH_LINK_KEY, and the default locations are moved to an empty folder.
class NodeLinkStart : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("tsmh_node_link_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    for (const char* name : {tsmh::bridge::kLinkKeyEnv, "HOME", "XDG_CONFIG_HOME"}) {
      const char* value = std::getenv(name);
      saved_.push_back({name, value ? std::optional<std::string>(value) : std::nullopt});
    }
    unsetenv(tsmh::bridge::kLinkKeyEnv);
    setenv("HOME", dir_.c_str(), 1);
    setenv("XDG_CONFIG_HOME", (dir_ / "config").c_str(), 1);
  }
  void TearDown() override {
    for (const auto& [name, value] : saved_) {
      if (value)
        setenv(name, value->c_str(), 1);
      else
        unsetenv(name);
    }
    fs::remove_all(dir_);
  }
  // Runs start_node_link and returns its status; `err` gets its stderr.
  int start(const NodeLinkOptions& o, NodeLink& link, std::string& err) {
    ::testing::internal::CaptureStderr();
    const int status = start_node_link("node-under-test", o, link);
    err = ::testing::internal::GetCapturedStderr();
    return status;
  }
  fs::path dir_;
  std::vector<std::pair<const char*, std::optional<std::string>>> saved_;
};

TEST_F(NodeLinkStart, NoKeyOnANetworkUrlIsRefusedWithExit2) {
  NodeLinkOptions o;
  o.url = "udpm://239.255.76.67:7667?ttl=1";
  NodeLink link;
  std::string err;
  EXPECT_EQ(start(o, link, err), 2);
  EXPECT_EQ(err.rfind("node-under-test: error: ", 0), 0U) << err;
  EXPECT_NE(err.find("tsm-link keygen"), std::string::npos) << err;  // says how to make a key
  EXPECT_EQ(link.lcm, nullptr);                                 // LCM never started
  EXPECT_EQ(link.signer, nullptr);
}

TEST_F(NodeLinkStart, ARepeatedTtlIsAnErrorNotHostLocal) {
  NodeLinkOptions o;
  o.url = "udpm://239.255.76.67:7667?ttl=0&ttl=1";
  NodeLink link;
  std::string err;
  EXPECT_EQ(start(o, link, err), 2);
  EXPECT_EQ(err.rfind("node-under-test: error: ", 0), 0U) << err;
  EXPECT_NE(err.find("ttl"), std::string::npos) << err;
  EXPECT_EQ(link.lcm, nullptr);
}

TEST_F(NodeLinkStart, InsecureRunsUnkeyedOnANetworkUrl) {
  NodeLinkOptions o;
  o.url = "udpm://239.255.76.67:7699?ttl=1";  // the URL the first test refuses without the flag
  o.security.insecure = true;
  NodeLink link;
  std::string err;
  const int status = start(o, link, err);
  if (status == 1 && err.find("cannot start LCM at udpm://") != std::string::npos)
    GTEST_SKIP() << "no multicast route: " << err;
  ASSERT_EQ(status, 0) << err;
  EXPECT_EQ(err.rfind("node-under-test: ", 0), 0U) << err;
  EXPECT_EQ(err.find("error"), std::string::npos) << err;
  ASSERT_NE(link.lcm, nullptr);
  EXPECT_TRUE(link.lcm->good());
  EXPECT_EQ(link.signer, nullptr);
  EXPECT_EQ(link.verifier, nullptr);
  EXPECT_EQ(link.session, nullptr);
}

TEST_F(NodeLinkStart, AKeyBringsSignerVerifierAndARearmingSession) {
  const auto key = tsmh::bridge::LinkKey::generate();
  const fs::path file = dir_ / "link.key";
  key.save(file);
  NodeLinkOptions o;
  o.url = "memq://";
  o.security.key_file = file.string();
  NodeLink link;
  std::string err;
  ASSERT_EQ(start(o, link, err), 0) << err;
  EXPECT_NE(err.find(key.fingerprint()), std::string::npos) << err;  // the notice names the key
  ASSERT_NE(link.lcm, nullptr);
  ASSERT_NE(link.signer, nullptr);
  ASSERT_NE(link.verifier, nullptr);
  ASSERT_NE(link.session, nullptr);
  EXPECT_EQ(link.security.key->bytes(), key.bytes());
}

TEST_F(NodeLinkStart, AMissingKeyFileIsAnErrorNotAFallback) {
  NodeLinkOptions o;
  o.url = "memq://";
  o.security.key_file = (dir_ / "no-such.key").string();
  NodeLink link;
  std::string err;
  EXPECT_EQ(start(o, link, err), 2);
  EXPECT_NE(err.find("no-such.key"), std::string::npos) << err;
  EXPECT_EQ(link.lcm, nullptr);
}

TEST_F(NodeLinkStart, HostOnlyUdpmStartsUnkeyedAndConfined) {
  NodeLinkOptions o;
  o.url = "udpm://239.255.76.67:7667?ttl=0";
  NodeLink link;
  std::string err;
  const int status = start(o, link, err);
  if (status == 1 && err.find("cannot start LCM") != std::string::npos)
    GTEST_SKIP() << "no multicast route: " << err;
  ASSERT_EQ(status, 0) << err;
  ASSERT_NE(link.lcm, nullptr);
  EXPECT_EQ(link.signer, nullptr);
}

}  // namespace
