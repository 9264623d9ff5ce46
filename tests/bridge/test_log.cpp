// LCM logs with the real tools: lcm-logger records what we publish, our
// reader (and `tsm convert`, when built) turns it into rows; lcm-logplayer
// replays a log into our Receiver.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <lcm/lcm-cpp.hpp>
#include <set>
#include <sstream>
#include <thread>

#include "bridge/link_auth.hpp"
#include "bridge/log_reader.hpp"
#include "bridge/receiver.hpp"
#include "process.hpp"
#include "realtime/clock.hpp"
#include "test_support.hpp"

namespace tsmh::bridge {
namespace {

using namespace std::chrono_literals;
namespace fs = std::filesystem;

fs::path temp_dir() {
  const fs::path dir = fs::temp_directory_path() / test::cat("tsmh_bridge_", test::unique_prefix());
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Keeps the logs of a failed test for inspection.
void remove_unless_failed(const fs::path& dir) {
  if (::testing::Test::HasFailure())
    std::cerr << "kept " << dir << " for inspection\n";
  else
    fs::remove_all(dir);
}

// What lcm-logger actually wrote, read independently of read_joint_series.
struct Recorded {
  fs::path log;
  std::set<std::int64_t> state_seqs, truth_seqs;
  std::size_t state_events = 0, truth_events = 0;
  std::set<std::int64_t> both() const {
    std::set<std::int64_t> out;
    std::set_intersection(state_seqs.begin(), state_seqs.end(), truth_seqs.begin(),
                          truth_seqs.end(), std::inserter(out, out.end()));
    return out;
  }
};

Recorded read_back(const fs::path& log, const std::string& prefix) {
  Recorded r;
  r.log = log;
  const std::string state = channel_name(prefix, Channel::kSlaveState);
  const std::string truth = channel_name(prefix, Channel::kSlaveTruth);
  lcm::LogFile in(log.string(), "r");
  Decoder<SlaveStateSample> sd;
  Decoder<SlaveTruthSample> td;
  SlaveStateSample s;
  SlaveTruthSample t;
  for (const lcm::LogEvent* ev = in.readNextEvent(); ev != nullptr; ev = in.readNextEvent()) {
    const auto n = static_cast<std::size_t>(ev->datalen);
    if (ev->channel == state) {
      ++r.state_events;
      if (!sd.decode(ev->data, n, s)) r.state_seqs.insert(s.seq);
    } else if (ev->channel == truth) {
      ++r.truth_events;
      if (!td.decode(ev->data, n, t)) r.truth_seqs.insert(t.seq);
    }
  }
  return r;
}

// Publishes `count` SLAVE_STATE + SLAVE_TRUTH messages from the peer process
// while lcm-logger records the prefix's channels.
//
// lcm-logger is best effort: its subscription queue holds 30 messages, so a
// stall of the logger on a busy machine loses some. The tests therefore check
// the conversion against what the log really holds (read back independently)
// and only require that most of the stream was recorded.
Recorded record_with_logger(const fs::path& dir, const std::string& prefix, int count) {
  const fs::path log = dir / "slave.lcmlog";
  const std::string url = test::test_url();
  test::Background logger({TSMH_LCM_LOGGER, "-q", "-f", "--flush-interval=10",
                           test::cat("--lcm-url=", url),
                           test::cat("--channel=", regex_escape(prefix), ".*"), log.string()});
  EXPECT_TRUE(logger.started());
  // Wait until the logger is listening: publish a probe until it lands in the file.
  auto probe = open_lcm(url);
  auto poke = [&] {
    const char byte = 0;
    probe->publish(prefix + "PROBE", &byte, 1);
    std::this_thread::sleep_for(20ms);
  };
  const bool listening = test::wait_until(
      [&] {
        poke();
        return fs::exists(log) && fs::file_size(log) > 0;
      },
      10s);
  EXPECT_TRUE(listening) << "lcm-logger never recorded the probe";
  // Synchronous publishing without catch-up bursts, easy on the logger's queue.
  const auto peer = test::run(
      {TSMH_BRIDGE_PEER, "publish-direct", url, prefix, std::to_string(count), "1000", "truth"});
  EXPECT_EQ(peer.exit_code, 0) << peer.output;
  // The logger writes behind and flushes its stdio buffer only when it writes
  // a later event: keep feeding it probes until the last message is on disk.
  test::wait_until(
      [&] {
        poke();
        return read_back(log, prefix).state_seqs.count(count - 1) == 1;
      },
      5s);
  poke();
  poke();
  logger.stop();
  Recorded r = read_back(log, prefix);
  EXPECT_GE(r.both().size(), static_cast<std::size_t>(count) / 2)
      << "lcm-logger recorded only " << r.state_seqs.size() << " SLAVE_STATE and "
      << r.truth_seqs.size() << " SLAVE_TRUTH of " << count;
  if (r.both().size() < static_cast<std::size_t>(count))
    std::cerr << "note: lcm-logger recorded " << r.both().size() << " of " << count
              << " state/truth pairs (best effort on a busy machine)\n";
  return r;
}

// The seq a make_state() row of joint `joint` was built from (x_in = 0.001 seq + joint).
std::int64_t seq_of_row(double x_in, int joint) {
  return std::llround((x_in - joint) / 0.001);
}

TEST(LcmLog, LoggerRoundTripThroughOurReader) {
  const fs::path dir = temp_dir();
  const std::string prefix = test::unique_prefix();
  const Recorded rec = record_with_logger(dir, prefix, 250);
  ASSERT_TRUE(is_lcm_log(rec.log));

  const JointSeries js = read_joint_series(rec.log, 1, prefix);
  EXPECT_EQ(js.state_messages, rec.state_events);
  EXPECT_EQ(js.truth_messages, rec.truth_events);
  const std::set<std::int64_t> both = rec.both();
  ASSERT_EQ(js.rows(), both.size()) << "one row per seq with both SLAVE_STATE and SLAVE_TRUTH";
  EXPECT_EQ(js.rows_without_truth, rec.state_seqs.size() - both.size());
  EXPECT_EQ(js.radius_m, 0.01);
  EXPECT_EQ(js.t.front(), 0.0);
  // Each row is the right message: values built by make_state/make_truth from its seq.
  std::int64_t last_seq = -1;
  for (std::size_t i = 0; i < js.rows(); ++i) {
    const std::int64_t seq = seq_of_row(js.x_in[i], 1);
    ASSERT_EQ(both.count(seq), 1U) << "row " << i;
    ASSERT_GT(seq, last_seq) << "rows in seq order";
    if (i > 0) {
      ASSERT_GT(js.t[i], js.t[i - 1]) << "row " << i;
    }
    ASSERT_EQ(js.x_in[i], test::make_state(seq, 0).x_in[1]) << "row " << i;
    ASSERT_EQ(js.T1[i], test::make_state(seq, 0).T1[1]);
    ASSERT_EQ(js.tau_out[i], test::make_truth(seq, 0).tau_out[1]) << "matched by seq";
    last_seq = seq;
  }
  EXPECT_EQ(js.x_out.size(), js.rows());

  try {
    read_joint_series(rec.log, 5, prefix);
    FAIL() << "joint 5 does not exist";
  } catch (const LogError& e) {
    EXPECT_NE(std::string(e.what()).find("has 2 joint(s)"), std::string::npos) << e.what();
  }
  try {
    read_joint_series(rec.log, 0, "NOPE_");
    FAIL() << "no such prefix";
  } catch (const LogError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  test::cat(prefix, "SLAVE_STATE (", std::to_string(rec.state_events), ")")),
              std::string::npos)
        << "lists the channels present: " << e.what();
  }
  remove_unless_failed(dir);
}

#ifdef TSMH_TSM_BIN
TEST(LcmLog, LoggerRoundTripThroughTsmConvert) {
  const fs::path dir = temp_dir();
  const std::string prefix = test::unique_prefix();
  const Recorded rec = record_with_logger(dir, prefix, 200);
  const fs::path csv = dir / "out.csv";
  const auto r = test::run({TSMH_TSM_BIN, "convert", rec.log.string(), "--output", csv.string(),
                            "--joint", "0", "--prefix", prefix});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(csv);
  std::string line, header;
  std::vector<std::string> rows;
  bool radius = false;
  while (std::getline(in, line)) {
    if (line.rfind('#', 0) == 0) {
      radius = radius || line.find("radius_m: 0.01") != std::string::npos;
      continue;
    }
    if (header.empty()) {
      header = line;
      continue;
    }
    rows.push_back(line);
  }
  EXPECT_TRUE(radius) << "'# radius_m:' comment";
  EXPECT_EQ(header, "t,x_in,tau_in,tau_out,x_out,T1,T3");
  const std::set<std::int64_t> both = rec.both();
  ASSERT_EQ(rows.size(), both.size());
  // Every row is the message of its seq: x_in, tau_in = R (T1 - T3), tau_out.
  for (const std::string& row : rows) {
    std::istringstream cells(row);
    std::vector<double> v;
    for (std::string cell; std::getline(cells, cell, ',');)
      v.push_back(std::stod(cell));
    ASSERT_EQ(v.size(), 7U) << row;
    const std::int64_t seq = seq_of_row(v[1], 0);
    ASSERT_EQ(both.count(seq), 1U) << row;
    const SlaveStateSample s = test::make_state(seq, 0);
    EXPECT_DOUBLE_EQ(v[1], s.x_in[0]) << row;
    EXPECT_NEAR(v[2], 0.01 * (s.T1[0] - s.T3[0]), 1e-12) << row;
    EXPECT_DOUBLE_EQ(v[3], test::make_truth(seq, 0).tau_out[0]) << row;
    EXPECT_DOUBLE_EQ(v[5], s.T1[0]) << row;
  }
  remove_unless_failed(dir);
}
#endif

// Writes 100 SLAVE_STATE events (seq 0..99, 1 ms apart) and one corrupt event.
void write_replay_log(const fs::path& log, const std::string& channel) {
  lcm::LogFile out(log.string(), "w");
  ASSERT_TRUE(out.good());
  const std::int64_t t0 = realtime::monotonic_utime();
  std::vector<std::uint8_t> bytes;
  for (int i = 0; i < 100; ++i) {
    encode_sample(test::make_state(i, t0 + i * 1000), bytes);
    lcm::LogEvent ev{};
    ev.timestamp = 1'700'000'000'000'000 + i * 1000;  // 1 kHz, as recorded
    ev.channel = channel;
    ev.datalen = static_cast<std::int32_t>(bytes.size());
    ev.data = bytes.data();
    ASSERT_EQ(out.writeEvent(&ev), 0);
  }
  std::uint8_t junk[7] = {9, 9, 9, 9, 9, 9, 9};
  lcm::LogEvent ev{};
  ev.timestamp = 1'700'000'000'100'000;
  ev.channel = channel;
  ev.datalen = sizeof junk;
  ev.data = junk;
  ASSERT_EQ(out.writeEvent(&ev), 0);
}

TEST(LcmLog, LogplayerReplaysIntoOurReceiver) {
  const fs::path dir = temp_dir();
  const std::string prefix = test::unique_prefix();
  const std::string channel = channel_name(prefix, Channel::kSlaveState);
  const fs::path log = dir / "replay.lcmlog";
  write_replay_log(log, channel);

  Receiver rx({.url = test::test_url(), .prefix = prefix});
  // Logged utimes are from the past: no latency, but ordering still applies.
  auto& inbox = rx.subscribe<SlaveStateSample>({.expected_joints = 2, .clocks_shared = false});
  rx.start();
  const auto player =
      test::run({TSMH_LCM_LOGPLAYER, test::cat("--lcm-url=", test::test_url()), log.string()});
  ASSERT_EQ(player.exit_code, 0) << player.output;
  ASSERT_TRUE(test::wait_until([&] { return inbox.stats().received == 101; }))
      << "received " << inbox.stats().received;
  const ChannelStats st = inbox.stats();
  EXPECT_EQ(st.accepted, 100U);
  EXPECT_EQ(st.rejected(RejectReason::kDecode), 1U);
  SlaveStateSample s;
  ASSERT_EQ(inbox.latest(s), 100U);
  EXPECT_EQ(s.seq, 99);
  remove_unless_failed(dir);
}

// An authenticated recording: SLAVE_STATE seq 0..49 signed with `key`, and
// (when `injected`) 10 unsigned events with seq 100..109 between them, as a
// sender without the key would leave in the log.
void write_signed_log(const fs::path& log, const std::string& channel,
                      std::shared_ptr<const LinkKey> key, bool injected) {
  lcm::LogFile out(log.string(), "w");
  ASSERT_TRUE(out.good());
  const auto signer = key ? std::make_unique<MessageSigner>(key) : nullptr;
  std::vector<std::uint8_t> bytes;
  std::int64_t event = 0;
  auto write = [&](std::int64_t seq, bool sign) {
    encode_sample(test::make_state(seq, 1000 + 1000 * event), bytes);
    if (sign) {
      const std::size_t n = bytes.size();
      bytes.resize(n + kAuthTrailerBytes);
      signer->sign(channel, bytes.data(), n, bytes.data() + n);
    }
    lcm::LogEvent ev{};
    ev.timestamp = 1'700'000'000'000'000 + event++ * 1000;
    ev.channel = channel;
    ev.datalen = static_cast<std::int32_t>(bytes.size());
    ev.data = bytes.data();
    ASSERT_EQ(out.writeEvent(&ev), 0);
  };
  for (int i = 0; i < 50; ++i) {
    write(i, signer != nullptr);
    if (injected && i % 5 == 0) write(100 + i / 5, false);
  }
}

std::string error_of(const fs::path& log, const std::string& prefix, const LogReadOptions& o) {
  try {
    (void)read_joint_series(log, 0, prefix, o);
  } catch (const LogError& e) {
    return e.what();
  }
  return "no error";
}

TEST(LcmLog, SignedLogIsVerifiedOrExplicitlySkipped) {
  const fs::path dir = temp_dir();
  const std::string prefix = test::unique_prefix();
  const std::string channel = channel_name(prefix, Channel::kSlaveState);
  const auto key = std::make_shared<const LinkKey>(LinkKey::generate());
  const fs::path log = dir / "signed.lcmlog";
  write_signed_log(log, channel, key, /*injected=*/true);

  // With the key: the 50 signed events, the 10 unsigned ones left out and counted.
  const JointSeries js = read_joint_series(log, 0, prefix, {.verify_key = key.get()});
  EXPECT_EQ(js.rows(), 50U);
  EXPECT_EQ(js.state_messages, 60U);
  EXPECT_EQ(js.skipped_no_mac, 10U);
  EXPECT_EQ(js.skipped_bad_mac, 0U);
  EXPECT_FALSE(js.no_macs);
  EXPECT_DOUBLE_EQ(js.x_in.back(), test::make_state(49, 0).x_in[0]) << "an authentic row";
  // Another key: nothing authentic, and the error says what to do.
  const LinkKey other = LinkKey::generate();
  const std::string wrong = error_of(log, prefix, {.verify_key = &other});
  EXPECT_NE(wrong.find("50 whose MAC does not verify"), std::string::npos) << wrong;
  EXPECT_NE(wrong.find("--skip-mac"), std::string::npos) << wrong;
  // No key: MACs present, so using them unverified needs --skip-mac.
  const std::string none = error_of(log, prefix, {});
  EXPECT_NE(none.find("carry a MAC"), std::string::npos) << none;
  EXPECT_NE(none.find("--key"), std::string::npos) << none;
  // --skip-mac: every event, trailers stripped, none verified.
  const JointSeries all = read_joint_series(log, 0, prefix, {.skip_mac = true});
  EXPECT_EQ(all.state_messages, 60U);
  EXPECT_EQ(all.skipped_invalid, 0U) << "the trailer is stripped before decoding";
  EXPECT_GE(all.rows(), 50U);

  // A log from before authentication, read with a key: used, and flagged.
  const fs::path old_log = dir / "unsigned.lcmlog";
  write_signed_log(old_log, channel, nullptr, false);
  const JointSeries old = read_joint_series(old_log, 0, prefix, {.verify_key = key.get()});
  EXPECT_EQ(old.rows(), 50U);
  EXPECT_TRUE(old.no_macs);

#ifdef TSMH_TSM_BIN
  const fs::path key_file = dir / "link.key";
  key->save(key_file);
  const fs::path csv = dir / "out.csv";
  // The environment's key search must not find a key of the machine's user.
  const std::vector<std::string> env = {"env", test::cat("XDG_CONFIG_HOME=", dir.string()),
                                        "TSMH_LINK_KEY="};
  auto tsm = [&](std::vector<std::string> more) {
    std::vector<std::string> argv = env;
    argv.insert(argv.end(), {TSMH_TSM_BIN, "convert", log.string(), "--output", csv.string(),
                             "--prefix", prefix});
    argv.insert(argv.end(), more.begin(), more.end());
    return test::run(argv);
  };
  const auto verified = tsm({"--key", key_file.string()});
  EXPECT_EQ(verified.exit_code, 0) << verified.output;
  EXPECT_NE(verified.output.find("50 rows"), std::string::npos) << verified.output;
  EXPECT_NE(verified.output.find("MACs verified, left out 10 without and 0 with a bad MAC"),
            std::string::npos)
      << verified.output;
  const auto refused = tsm({});
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("--skip-mac"), std::string::npos) << refused.output;
  const auto skipped = tsm({"--skip-mac"});
  EXPECT_EQ(skipped.exit_code, 0) << skipped.output;
  EXPECT_NE(skipped.output.find("MACs not checked (--skip-mac)"), std::string::npos)
      << skipped.output;
#endif
  remove_unless_failed(dir);
}

// LCM's file:// provider as the Receiver's URL: a log replayed straight into
// the bridge (e.g. `haptic-server --lcm-url file:///run.lcmlog?speed=1`). At
// the end of the log LCM's handle() fails; the receive thread must back off,
// not spin.
TEST(LcmLog, FileProviderUrlFeedsAReceiver) {
  const fs::path dir = temp_dir();
  const std::string prefix = test::unique_prefix();
  const fs::path log = dir / "replay.lcmlog";
  write_replay_log(log, channel_name(prefix, Channel::kSlaveState));
  Receiver rx({.url = test::cat("file://", log.string(), "?speed=0"), .prefix = prefix});
  auto& inbox = rx.subscribe<SlaveStateSample>({.expected_joints = 2, .clocks_shared = false});
  rx.start();
  ASSERT_TRUE(test::wait_until([&] { return inbox.stats().received == 101; }));
  std::this_thread::sleep_for(300ms);  // past the end of the log
  EXPECT_EQ(inbox.stats().accepted, 100U);
  EXPECT_LT(rx.transport_errors(), 100U) << "the receive thread spun on a failing descriptor";
  rx.stop();
  remove_unless_failed(dir);
}

TEST(LcmLog, NotALogIsAClearError) {
  const fs::path dir = temp_dir();
  const fs::path bogus = dir / "data.csv";
  std::ofstream(bogus) << "t,x_in\n0,1\n";
  EXPECT_FALSE(is_lcm_log(bogus));
  try {
    read_joint_series(bogus, 0);
    FAIL();
  } catch (const LogError& e) {
    EXPECT_NE(std::string(e.what()).find("not an LCM log"), std::string::npos) << e.what();
  }
  remove_unless_failed(dir);
}

}  // namespace
}  // namespace tsmh::bridge
