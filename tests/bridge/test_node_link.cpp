// The start-up of the standalone nodes (bridge/node_link.hpp): the refusal
// to run unkeyed on a network URL, the signer/verifier/session that come
// with a key, and the messages and exit statuses the programs print; the
// node's period (NodeTicker): LCM drained, a pending stop signal or the end of
// the duration ends it, an overrun re-bases the schedule.

#include <gtest/gtest.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <thread>

#include "bridge/link_auth.hpp"
#include "bridge/link_security.hpp"
#include "bridge/node_link.hpp"
#include "realtime/clock.hpp"

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
  EXPECT_EQ(link.lcm, nullptr);                                      // LCM never started
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

// A memq link (no key, no session): the ticker's loop alone.
NodeLink memq_link() {
  NodeLink link;
  link.lcm = std::make_unique<lcm::LCM>("memq://");
  return link;
}

sigset_t no_stop_signals() {
  sigset_t set;
  sigemptyset(&set);
  return set;
}

TEST(NodeTicker, EachPeriodDrainsWhatLcmReceived) {
  NodeLink link = memq_link();
  ASSERT_TRUE(link.lcm->good());
  int received = 0;
  link.lcm->subscribeFunction<int*>(
      "NODE_TICKER_TEST", [](const lcm::ReceiveBuffer*, const std::string&, int* n) { ++*n; },
      &received);
  tsmh::bridge::NodeTicker ticker(link, 1000.0, 0.0, no_stop_signals());
  const std::uint8_t byte = 7;
  for (int i = 0; i < 3; ++i)
    link.lcm->publish("NODE_TICKER_TEST", &byte, 1);
  ASSERT_TRUE(ticker.next());
  EXPECT_EQ(received, 3);  // all of them, in the one period
  EXPECT_GT(ticker.now_ns(), 0);
  EXPECT_EQ(ticker.period_ns(), 1'000'000);
}

TEST(NodeTicker, EndsAtTheDurationAfterNoMorePeriodsThanFitInIt) {
  NodeLink link = memq_link();
  const std::int64_t start = tsmh::realtime::monotonic_now_ns();
  tsmh::bridge::NodeTicker ticker(link, 1000.0, 0.03, no_stop_signals());
  int periods = 0;
  while (ticker.next())
    ++periods;
  EXPECT_GE(tsmh::realtime::monotonic_now_ns() - start, 30'000'000);
  EXPECT_GE(periods, 1);
  EXPECT_LE(periods, 30);  // deadlines 1, 2, ... 30 ms after the start
}

TEST(NodeTicker, APendingStopSignalEndsItWithoutWaiting) {
  sigset_t stop;
  sigemptyset(&stop);
  sigaddset(&stop, SIGUSR2);
  sigset_t old;
  ASSERT_EQ(pthread_sigmask(SIG_BLOCK, &stop, &old), 0);
  NodeLink link = memq_link();
  tsmh::bridge::NodeTicker ticker(link, 1.0, 0.0, stop);  // one period a second
  ASSERT_EQ(pthread_kill(pthread_self(), SIGUSR2), 0);
  const std::int64_t before = tsmh::realtime::monotonic_now_ns();
  EXPECT_FALSE(ticker.next());
  EXPECT_LT(tsmh::realtime::monotonic_now_ns() - before, 500'000'000);  // not the 1 s period
  const timespec none{0, 0};
  EXPECT_EQ(sigtimedwait(&stop, nullptr, &none), SIGUSR2);  // the signal is left pending
  pthread_sigmask(SIG_SETMASK, &old, nullptr);
}

TEST(NodeTicker, AfterAnOverrunTheNextPeriodsWaitForDeadlinesAhead) {
  NodeLink link = memq_link();
  tsmh::bridge::NodeTicker ticker(link, 1000.0, 0.0, no_stop_signals());
  ASSERT_TRUE(ticker.next());
  std::this_thread::sleep_for(std::chrono::milliseconds(30));  // 30 deadlines missed
  const std::int64_t before = tsmh::realtime::monotonic_now_ns();
  for (int i = 0; i < 5; ++i)
    ASSERT_TRUE(ticker.next());
  // Re-based: five periods on deadlines after the stall take >= 4 periods;
  // running the missed deadlines back to back would take none.
  EXPECT_GE(tsmh::realtime::monotonic_now_ns() - before, 4'000'000);
}

TEST(NodeLinkEnd, ASessionFaultSaysWhatTheNodeDidAndExits4) {
  ::testing::internal::CaptureStderr();
  const int status = tsmh::bridge::session_fault_exit("node-under-test", "master",
                                                      tsmh::bridge::SessionFault{0xabc, 0x12},
                                                      "holding", 3, "commands");
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(status, 4);
  EXPECT_EQ(err.rfind("node-under-test: FAULT: another master session on the link (sender "
                      "0000000000000abc naming 0000000000000012: ",
                      0),
            0U)
      << err;
  EXPECT_NE(err.find("; holding, exit 4 (3 such commands)\n"), std::string::npos) << err;
}

}  // namespace
