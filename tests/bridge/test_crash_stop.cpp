// The hand-made LCM udpm datagram and the crash handler (bridge/udpm_frame.hpp,
// bridge/crash_stop.hpp) over real udpm on this host (ttl=0): LCM itself
// must receive the datagram, and a process that sends itself a core-dumping
// signal must die of that signal with the prepared message the last one on
// its channel, although another thread of it kept publishing until then.
#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "bridge/crash_stop.hpp"
#include "bridge/stop_signals.hpp"
#include "bridge/udpm_frame.hpp"
#include "test_support.hpp"

namespace tsmh::bridge {
namespace {

using namespace std::chrono_literals;

TEST(UdpmFrame, EndpointAsLcmReadsTheUrl) {
  const auto e = udpm_endpoint("udpm://239.255.76.67:7741?ttl=0&recv_buf_size=2097152");
  ASSERT_TRUE(e);
  EXPECT_EQ(ntohs(e->group.sin_port), 7741);
  EXPECT_EQ(ntohl(e->group.sin_addr.s_addr), 0xEFFF4C43u);  // 239.255.76.67
  EXPECT_EQ(e->ttl, 0);
  const auto defaults = udpm_endpoint("udpm://");
  ASSERT_TRUE(defaults);
  EXPECT_EQ(ntohs(defaults->group.sin_port), 7667);
  EXPECT_EQ(udpm_endpoint("udpm://239.255.76.67:7667?ttl=1")->ttl, 1);
  EXPECT_FALSE(udpm_endpoint("memq://"));
  EXPECT_FALSE(udpm_endpoint("udpm://not-an-address:7667"));
  EXPECT_FALSE(udpm_endpoint("udpm://239.255.76.67:70000"));
  EXPECT_FALSE(udpm_endpoint("udpm://239.255.76.67:7667?ttl=x"));
}

TEST(UdpmFrame, RefusesWhatLcmWouldNotSendInOneDatagram) {
  std::uint8_t out[64];
  const std::uint8_t payload[4] = {1, 2, 3, 4};
  EXPECT_EQ(frame_udpm_short("", 0, payload, 4, out, sizeof out), 0u);
  EXPECT_EQ(frame_udpm_short(std::string(64, 'A'), 0, payload, 4, out, sizeof out), 0u);
  EXPECT_EQ(frame_udpm_short("CH", 0, payload, 4, out, 14), 0u);  // needs 8 + 3 + 4
  EXPECT_EQ(frame_udpm_short("CH", 0x01020304, payload, 4, out, 15), 15u);
  const std::uint8_t expected[15] = {'L', 'C', '0', '2', 1, 2, 3, 4, 'C', 'H', 0, 1, 2, 3, 4};
  EXPECT_EQ(std::vector<std::uint8_t>(out, out + 15),
            std::vector<std::uint8_t>(expected, expected + 15));
}

/// Every message on one channel, in arrival order.
class ChannelLog {
 public:
  explicit ChannelLog(const std::string& channel) : lcm_(test::test_url()) {
    lcm_.subscribe(channel, &ChannelLog::on_message, this);
    thread_ = std::thread([this] {
      while (running_)
        lcm_.handleTimeout(10);
    });
  }
  ~ChannelLog() {
    running_ = false;
    thread_.join();
  }
  std::vector<std::string> messages() {
    std::lock_guard lock(mutex_);
    return messages_;
  }

 private:
  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& /*channel*/) {
    std::lock_guard lock(mutex_);
    messages_.emplace_back(static_cast<const char*>(rbuf->data), rbuf->data_size);
  }

  lcm::LCM lcm_;
  std::mutex mutex_;
  std::vector<std::string> messages_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

TEST(UdpmFrame, LcmReceivesTheHandMadeDatagram) {
  const std::string channel = test::unique_prefix() + "FRAME";
  ChannelLog log(channel);
  const auto e = udpm_endpoint(test::test_url());
  ASSERT_TRUE(e);
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  const int ttl = e->ttl;
  setsockopt(fd, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof ttl);
  const std::string payload = std::string("payload\0with a NUL", 18);
  std::uint8_t out[256];
  const std::size_t n =
      frame_udpm_short(channel, 42, reinterpret_cast<const std::uint8_t*>(payload.data()),
                       payload.size(), out, sizeof out);
  ASSERT_GT(n, 0u);
  ASSERT_EQ(sendto(fd, out, n, 0, reinterpret_cast<const sockaddr*>(&e->group), sizeof e->group),
            static_cast<ssize_t>(n));
  close(fd);
  ASSERT_TRUE(test::wait_until([&] { return !log.messages().empty(); }, 2s));
  EXPECT_EQ(log.messages().front(), payload);
}

// One process per signal (bridge_test_peer crash): it dies of the signal
// (exit status as the kernel gives it, core dumps off), and "crashed" is the
// last message heard on the channel although its "alive" thread kept
// publishing every 200 us through LCM until the end.
TEST(CrashStop, EveryCoreDumpingSignalSendsThePreparedDatagramLastThenEndsTheProcess) {
  for (int sig : CrashStop::kSignals) {
    SCOPED_TRACE(signal_name(sig));
    const std::string channel = test::unique_prefix() + "CRASH";
    ChannelLog log(channel);
    const std::vector<std::string> argv = {TSMH_BRIDGE_PEER, "crash", test::test_url(), channel,
                                           std::to_string(sig)};
    const pid_t pid = fork();
    if (pid == 0) {
      std::vector<char*> args;
      for (const auto& a : argv)
        args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
    ASSERT_GT(pid, 0);
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(status)) << "exit code " << WEXITSTATUS(status);
    EXPECT_EQ(WTERMSIG(status), sig);
    EXPECT_FALSE(WCOREDUMP(status)) << "core dumps were off";
    std::this_thread::sleep_for(200ms);  // the last datagrams arrive
    const auto messages = log.messages();
    ASSERT_GE(messages.size(), 2u) << "the peer's alive thread was never heard";
    EXPECT_EQ(messages.front(), "alive");
    EXPECT_EQ(messages.back(), "crashed") << messages.size() << " messages";
  }
}

// The same for a device node (the hid console's hidraw node in haptic-server;
// a FIFO here, where no console is plugged in): the prepared report, written
// through the CrashStop's own descriptor, is the last record on the node,
// after the "driver's" records, and the process dies of the signal. (The
// driver's descriptor is silenced too, but its 200 us writes rarely fall in
// the microseconds between the report and the end: this test cannot tell.)
TEST(CrashStop, ThePreparedReportIsTheLastOneWrittenToTheDeviceNode) {
  for (int sig : {SIGSEGV, SIGABRT}) {
    SCOPED_TRACE(signal_name(sig));
    const std::string fifo =
        test::cat("/tmp/tsmh-crash-node-", std::to_string(getpid()), "-", std::to_string(sig));
    unlink(fifo.c_str());
    ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
    const int reader = open(fifo.c_str(), O_RDONLY | O_NONBLOCK);
    ASSERT_GE(reader, 0);
    const std::vector<std::string> argv = {TSMH_BRIDGE_PEER, "crash-node", fifo,
                                           std::to_string(sig)};
    const pid_t pid = fork();
    if (pid == 0) {
      std::vector<char*> args;
      for (const auto& a : argv)
        args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      execv(args[0], args.data());
      _exit(127);
    }
    ASSERT_GT(pid, 0);
    // Drain the FIFO until the peer has ended and nothing more comes.
    std::string bytes;
    int status = 0;
    bool ended = false;
    const auto deadline = std::chrono::steady_clock::now() + 10s;
    while (std::chrono::steady_clock::now() < deadline) {
      pollfd p{reader, POLLIN, 0};
      poll(&p, 1, 5);
      char buf[4096];
      const ssize_t n = read(reader, buf, sizeof buf);
      if (n > 0) bytes.append(buf, static_cast<std::size_t>(n));
      if (!ended && waitpid(pid, &status, WNOHANG) == pid) ended = true;
      if (ended && n <= 0) break;
    }
    close(reader);
    unlink(fifo.c_str());
    ASSERT_TRUE(ended);
    ASSERT_TRUE(WIFSIGNALED(status)) << "exit code " << WEXITSTATUS(status);
    EXPECT_EQ(WTERMSIG(status), sig);
    ASSERT_GE(bytes.size(), 16u) << "the peer's torque thread was never heard";
    ASSERT_EQ(bytes.size() % 8, 0u);  // writes of 8 bytes into a FIFO are atomic
    EXPECT_EQ(bytes.substr(0, 8), "torque!!");
    EXPECT_EQ(bytes.substr(bytes.size() - 8), "zeroed!!") << bytes.size() / 8 << " records";
  }
}

}  // namespace
}  // namespace tsmh::bridge
