// Message authentication (bridge/link_auth.hpp, link_security.hpp): the MAC,
// the replay window, freshness, key files and the key search order; over
// real udpm, rogue publishers (no key, wrong key, replayed, reordered, stale)
// against a keyed Receiver.
#include <gtest/gtest.h>
#include <sodium.h>
#include <sys/stat.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <mutex>
#include <thread>
#include <vector>

#include "bridge/link_auth.hpp"
#include "bridge/link_security.hpp"
#include "bridge/receiver.hpp"
#include "bridge/sender.hpp"
#include "realtime/clock.hpp"
#include "test_support.hpp"

namespace tsmh::bridge {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using test::make_state;
using test::wait_until;

std::shared_ptr<const LinkKey> new_key() {
  return std::make_shared<const LinkKey>(LinkKey::generate());
}

/// payload + trailer signed by `signer` as (seq, time).
std::vector<std::uint8_t> signed_message(const MessageSigner& signer, std::string_view channel,
                                         std::vector<std::uint8_t> payload, std::uint64_t seq,
                                         std::int64_t time_us) {
  const std::size_t n = payload.size();
  payload.resize(n + kAuthTrailerBytes);
  signer.sign_as(channel, payload.data(), n, {signer.sender_id(), seq, time_us},
                 payload.data() + n);
  return payload;
}

std::vector<std::uint8_t> some_payload() {
  std::vector<std::uint8_t> bytes;
  encode_sample(make_state(7, 1000), bytes);
  return bytes;
}

AuthVerdict verdict(MessageVerifier& v, std::string_view channel,
                    const std::vector<std::uint8_t>& m, std::int64_t now_us) {
  return v.verify(channel, m.data(), m.size(), now_us).verdict;
}

constexpr std::int64_t kNow = 1'700'000'000'000'000;  // a fixed "receiver clock", us

TEST(LinkAuth, SignedMessageVerifiesAndGivesThePayloadSize) {
  const auto key = new_key();
  const MessageSigner signer(key);
  MessageVerifier verifier(key);
  const auto payload = some_payload();
  const auto m = signed_message(signer, "ARM1_MASTER_COMMAND", payload, 1, kNow);
  EXPECT_TRUE(has_auth_trailer(m.data(), m.size()));
  EXPECT_FALSE(has_auth_trailer(payload.data(), payload.size()));
  const AuthResult r = verifier.verify("ARM1_MASTER_COMMAND", m.data(), m.size(), kNow);
  EXPECT_EQ(r.verdict, AuthVerdict::kOk);
  EXPECT_EQ(r.payload_size, payload.size());
  EXPECT_EQ(r.trailer.sender_id, signer.sender_id());
  EXPECT_EQ(r.trailer.seq, 1U);
  EXPECT_EQ(verify_stored(*key, "ARM1_MASTER_COMMAND", m.data(), m.size()), AuthVerdict::kOk);
}

std::uint64_t u64_at(const std::vector<std::uint8_t>& m, std::size_t offset) {
  std::uint64_t v = 0;
  for (int i = 7; i >= 0; --i)
    v = (v << 8) | m[offset + static_cast<std::size_t>(i)];
  return v;
}

TEST(LinkAuth, TrailerVersion2LayoutCarriesThePeerIdUnderTheMac) {
  const auto key = new_key();
  MessageSigner signer(key);
  signer.set_peer_id(0x1122334455667788ULL);
  const auto payload = some_payload();
  auto m = payload;
  m.resize(payload.size() + kAuthTrailerBytes);
  signer.sign_at("C", m.data(), payload.size(), 9, kNow, m.data() + payload.size());
  ASSERT_EQ(kAuthTrailerBytes, 72U);
  const std::size_t t = payload.size();
  EXPECT_EQ(std::string(m.begin() + static_cast<long>(t), m.begin() + static_cast<long>(t) + 4),
            "TSMA");
  EXPECT_EQ(m[t + 4], 2);
  EXPECT_EQ(m[t + 5] | m[t + 6] | m[t + 7], 0);
  EXPECT_EQ(u64_at(m, t + 8), signer.sender_id());
  EXPECT_EQ(u64_at(m, t + 16), 9U);
  EXPECT_EQ(u64_at(m, t + 24), static_cast<std::uint64_t>(kNow));
  EXPECT_EQ(u64_at(m, t + 32), 0x1122334455667788ULL);
  EXPECT_EQ(auth_trailer_size(m.data(), m.size()), kAuthTrailerBytes);
  MessageVerifier v(key);
  const AuthResult r = v.verify("C", m.data(), m.size(), kNow);
  ASSERT_EQ(r.verdict, AuthVerdict::kOk);
  EXPECT_EQ(r.trailer.peer_id, 0x1122334455667788ULL);
  EXPECT_EQ(r.payload_size, payload.size());
  // The peer id is signed: naming another peer breaks the MAC.
  m[t + 32] ^= 1;
  MessageVerifier fresh(key);
  EXPECT_EQ(verdict(fresh, "C", m, kNow), AuthVerdict::kBadMac);
}

// A version 1 trailer (64 bytes, MAC over bytes 0..31), as written before sessions.
std::vector<std::uint8_t> version1_message(const LinkKey& key, std::string_view channel,
                                           std::vector<std::uint8_t> payload, std::uint64_t id,
                                           std::uint64_t seq) {
  const std::size_t n = payload.size();
  payload.resize(n + kAuthTrailerV1Bytes);
  std::uint8_t* t = payload.data() + n;
  std::memcpy(t, "TSMA\x01\0\0\0", 8);
  for (int i = 0; i < 8; ++i) {
    t[8 + i] = static_cast<std::uint8_t>(id >> (8 * i));
    t[16 + i] = static_cast<std::uint8_t>(seq >> (8 * i));
    t[24 + i] = static_cast<std::uint8_t>(static_cast<std::uint64_t>(kNow) >> (8 * i));
  }
  crypto_auth_hmacsha512256_state st;
  crypto_auth_hmacsha512256_init(&st, key.bytes().data(), key.bytes().size());
  crypto_auth_hmacsha512256_update(&st, reinterpret_cast<const unsigned char*>(channel.data()),
                                   channel.size());
  const unsigned char zero = 0;
  crypto_auth_hmacsha512256_update(&st, &zero, 1);
  crypto_auth_hmacsha512256_update(&st, payload.data(), n);
  crypto_auth_hmacsha512256_update(&st, t, 32);
  crypto_auth_hmacsha512256_final(&st, t + 32);
  return payload;
}

TEST(LinkAuth, Version1IsReadInStoredLogsAndRefusedLive) {
  const auto key = new_key();
  const auto payload = some_payload();
  const auto m = version1_message(*key, "C", payload, 42, 1);
  EXPECT_EQ(auth_trailer_size(m.data(), m.size()), kAuthTrailerV1Bytes);
  EXPECT_EQ(verify_stored(*key, "C", m.data(), m.size()), AuthVerdict::kOk);
  EXPECT_EQ(verify_stored(*new_key(), "C", m.data(), m.size()), AuthVerdict::kBadMac);
  MessageVerifier live(key);
  EXPECT_EQ(verdict(live, "C", m, kNow), AuthVerdict::kVersion1)
      << "a live receiver needs a peer id to hold a session";
  MessageVerifier log(key, {.check_freshness = false, .accept_version_1 = true});
  const AuthResult r = log.verify("C", m.data(), m.size(), kNow);
  EXPECT_EQ(r.verdict, AuthVerdict::kOk);
  EXPECT_EQ(r.payload_size, payload.size());
  EXPECT_EQ(r.trailer.sender_id, 42U);
  EXPECT_EQ(r.trailer.peer_id, 0U);
}

TEST(LinkAuth, EveryAlteredByteIsRejected) {
  const auto key = new_key();
  const MessageSigner signer(key);
  const auto m = signed_message(signer, "C", some_payload(), 1, kNow);
  for (std::size_t i = 0; i < m.size(); ++i) {
    MessageVerifier verifier(key);  // fresh window: only the MAC can refuse
    auto bad = m;
    bad[i] ^= 0x01;
    const AuthVerdict v = verdict(verifier, "C", bad, kNow);
    // The magic and version bytes make it "no trailer"; every other byte the MAC covers.
    EXPECT_TRUE(v == AuthVerdict::kBadMac ||
                (v == AuthVerdict::kMissing && i >= m.size() - kAuthTrailerBytes &&
                 i < m.size() - kAuthTrailerBytes + 8))
        << "byte " << i << " flipped, verdict " << static_cast<int>(v);
  }
}

TEST(LinkAuth, WrongKeyAndOtherChannelAreBadMac) {
  const auto key = new_key();
  const MessageSigner signer(key);
  const auto m = signed_message(signer, "ARM1_MASTER_COMMAND", some_payload(), 1, kNow);
  MessageVerifier other_key(new_key());
  EXPECT_EQ(verdict(other_key, "ARM1_MASTER_COMMAND", m, kNow), AuthVerdict::kBadMac);
  MessageVerifier verifier(key);
  EXPECT_EQ(verdict(verifier, "ARM2_MASTER_COMMAND", m, kNow), AuthVerdict::kBadMac)
      << "the channel name is signed: one arm's command is not another's";
  EXPECT_EQ(verdict(verifier, "ARM1_MASTER_COMMAND", some_payload(), kNow), AuthVerdict::kMissing);
}

TEST(LinkAuth, ReplayWindowRefusesRepeatsAndTooOldButAcceptsReordering) {
  const auto key = new_key();
  const MessageSigner signer(key);
  MessageVerifier v(key);
  auto msg = [&](std::uint64_t seq) { return signed_message(signer, "C", {1, 2, 3}, seq, kNow); };
  EXPECT_EQ(verdict(v, "C", msg(10), kNow), AuthVerdict::kOk);
  EXPECT_EQ(verdict(v, "C", msg(10), kNow), AuthVerdict::kReplayed);
  EXPECT_EQ(verdict(v, "C", msg(12), kNow), AuthVerdict::kOk);
  EXPECT_EQ(verdict(v, "C", msg(11), kNow), AuthVerdict::kOk) << "late but never seen";
  EXPECT_EQ(verdict(v, "C", msg(11), kNow), AuthVerdict::kReplayed);
  EXPECT_EQ(verdict(v, "C", msg(12), kNow), AuthVerdict::kReplayed);
  // Slide the window by more than its width: everything before it is refused.
  const std::uint64_t top = 12 + MessageVerifier::kWindow + 5;
  EXPECT_EQ(verdict(v, "C", msg(top), kNow), AuthVerdict::kOk);
  EXPECT_EQ(verdict(v, "C", msg(13), kNow), AuthVerdict::kReplayed) << "older than the window";
  EXPECT_EQ(verdict(v, "C", msg(top - MessageVerifier::kWindow), kNow), AuthVerdict::kReplayed);
  EXPECT_EQ(verdict(v, "C", msg(top - MessageVerifier::kWindow + 1), kNow), AuthVerdict::kOk)
      << "the oldest number inside the window, never seen";
  // A slide by less than the width clears exactly the numbers it newly covers.
  EXPECT_EQ(verdict(v, "C", msg(top + 100), kNow), AuthVerdict::kOk);
  EXPECT_EQ(verdict(v, "C", msg(top + 50), kNow), AuthVerdict::kOk);
  EXPECT_EQ(verdict(v, "C", msg(top), kNow), AuthVerdict::kReplayed) << "still remembered";
}

TEST(LinkAuth, ForgedMessagesDoNotMoveTheWindow) {
  const auto key = new_key();
  const MessageSigner signer(key);
  const MessageSigner rogue(new_key());
  MessageVerifier v(key);
  EXPECT_EQ(verdict(v, "C", signed_message(signer, "C", {1}, 5, kNow), kNow), AuthVerdict::kOk);
  // Same sender id, huge seq, wrong key: if it moved the window, seq 6 would be "too old".
  auto forged = signed_message(rogue, "C", {1}, 1'000'000, kNow);
  const auto id = signer.sender_id();
  for (int i = 0; i < 8; ++i)  // overwrite the sender id (bytes 8..15 of the trailer)
    forged[forged.size() - kAuthTrailerBytes + 8 + static_cast<std::size_t>(i)] =
        static_cast<std::uint8_t>(id >> (8 * i));
  EXPECT_EQ(verdict(v, "C", forged, kNow), AuthVerdict::kBadMac);
  EXPECT_EQ(verdict(v, "C", signed_message(signer, "C", {1}, 6, kNow), kNow), AuthVerdict::kOk);
}

TEST(LinkAuth, StaleOrFutureSendTimeIsRefusedUnlessFreshnessIsOff) {
  const auto key = new_key();
  const MessageSigner signer(key);
  MessageVerifier v(key, {.max_age_us = 2'000'000});
  EXPECT_EQ(verdict(v, "C", signed_message(signer, "C", {1}, 1, kNow - 1'999'000), kNow),
            AuthVerdict::kOk);
  const AuthResult old = [&] {
    const auto m = signed_message(signer, "C", {1}, 2, kNow - 2'001'000);
    return v.verify("C", m.data(), m.size(), kNow);
  }();
  EXPECT_EQ(old.verdict, AuthVerdict::kStale);
  EXPECT_EQ(old.age_us, 2'001'000);
  EXPECT_EQ(verdict(v, "C", signed_message(signer, "C", {1}, 3, kNow + 2'001'000), kNow),
            AuthVerdict::kStale);
  EXPECT_EQ(verdict(v, "C", signed_message(signer, "C", {1}, 4, INT64_MIN), kNow),
            AuthVerdict::kStale)
      << "a hostile time must not overflow into 'fresh'";
  MessageVerifier log_reader(key, {.check_freshness = false});
  EXPECT_EQ(verdict(log_reader, "C", signed_message(signer, "C", {1}, 5, 0), kNow),
            AuthVerdict::kOk);
}

TEST(LinkAuth, EachSenderHasItsOwnWindowAndTheOldestIsForgotten) {
  const auto key = new_key();
  MessageVerifier v(key);
  std::vector<std::unique_ptr<MessageSigner>> senders;
  for (std::size_t i = 0; i <= MessageVerifier::kSenders; ++i)
    senders.push_back(std::make_unique<MessageSigner>(key));
  const auto first = signed_message(*senders[0], "C", {1}, 1, kNow);
  EXPECT_EQ(verdict(v, "C", first, kNow), AuthVerdict::kOk);
  for (std::size_t i = 1; i < MessageVerifier::kSenders; ++i)
    EXPECT_EQ(verdict(v, "C", signed_message(*senders[i], "C", {1}, 1, kNow), kNow),
              AuthVerdict::kOk)
        << "seq 1 of sender " << i << " is new";
  EXPECT_EQ(verdict(v, "C", first, kNow), AuthVerdict::kReplayed) << "all senders still held";
  EXPECT_EQ(verdict(v, "C", signed_message(*senders[0], "C", {1}, 2, kNow), kNow),
            AuthVerdict::kOk);  // sender 0 heard again: now sender 1 is the least recent
  // One more sender than the table holds: the least recently heard (sender 1) goes.
  EXPECT_EQ(verdict(v, "C", signed_message(*senders.back(), "C", {1}, 1, kNow), kNow),
            AuthVerdict::kOk);
  EXPECT_EQ(verdict(v, "C", first, kNow), AuthVerdict::kReplayed) << "sender 0 is still held";
  // The documented limit: a forgotten sender's fresh message passes once more
  // (max_age bounds how long that is possible).
  EXPECT_EQ(verdict(v, "C", signed_message(*senders[1], "C", {1}, 1, kNow), kNow),
            AuthVerdict::kOk);
}

TEST(LinkAuth, SignerNumbersMessagesFromOne) {
  const auto key = new_key();
  MessageSigner signer(key);
  MessageVerifier v(key);
  std::vector<std::uint8_t> m(10 + kAuthTrailerBytes, 0);
  for (std::uint64_t expect = 1; expect <= 3; ++expect) {
    signer.sign("C", m.data(), 10, m.data() + 10);
    const AuthResult r = v.verify("C", m.data(), m.size(), realtime::wall_clock_utime());
    EXPECT_EQ(r.verdict, AuthVerdict::kOk);
    EXPECT_EQ(r.trailer.seq, expect);
  }
  EXPECT_NE(MessageSigner(key).sender_id(), signer.sender_id()) << "random per signer";
}

// ---- key files and the search order -----------------------------------------

class KeyFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           test::cat("tsmh_keys_", std::to_string(getpid()), "_",
                     ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(KeyFiles, SaveCreatesMode0600AndLoadRoundTrips) {
  const auto key = LinkKey::generate();
  const fs::path file = dir_ / "sub" / "link.key";
  key.save(file);
  struct stat st {};
  ASSERT_EQ(stat(file.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600U);
  const auto back = LinkKey::load(file);
  EXPECT_EQ(back.bytes(), key.bytes());
  EXPECT_EQ(back.fingerprint(), key.fingerprint());
  EXPECT_NE(LinkKey::generate().fingerprint(), key.fingerprint());
  EXPECT_EQ(key.fingerprint().size(), 16U);
}

TEST_F(KeyFiles, SaveRefusesToOverwriteUnlessAsked) {
  const fs::path file = dir_ / "link.key";
  LinkKey::generate().save(file);
  try {
    LinkKey::generate().save(file);
    FAIL() << "overwrote an existing key";
  } catch (const LinkKeyError& e) {
    EXPECT_NE(std::string(e.what()).find("already exists"), std::string::npos) << e.what();
  }
  const auto replacement = LinkKey::generate();
  replacement.save(file, /*overwrite=*/true);
  EXPECT_EQ(LinkKey::load(file).bytes(), replacement.bytes());
}

TEST_F(KeyFiles, LoadRefusesAFileOthersCanRead) {
  const fs::path file = dir_ / "link.key";
  LinkKey::generate().save(file);
  chmod(file.c_str(), 0644);
  try {
    (void)LinkKey::load(file);
    FAIL() << "loaded a world-readable key";
  } catch (const LinkKeyError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file.string()), std::string::npos) << what;
    EXPECT_NE(what.find("0644"), std::string::npos) << what;
    EXPECT_NE(what.find("chmod 600"), std::string::npos) << what;
  }
  chmod(file.c_str(), 0640);
  EXPECT_THROW((void)LinkKey::load(file), LinkKeyError) << "group-readable";
  chmod(file.c_str(), 0400);
  EXPECT_NO_THROW((void)LinkKey::load(file));
}

TEST_F(KeyFiles, MalformedKeysSayWhatIsWrong) {
  auto write = [&](const std::string& text) {
    const fs::path file = dir_ / "bad.key";
    fs::remove(file);
    std::ofstream(file) << text;
    chmod(file.c_str(), 0600);
    return file;
  };
  auto error_of = [&](const std::string& text) {
    try {
      (void)LinkKey::load(write(text));
    } catch (const LinkKeyError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(error_of("abcd\n").find("64 hex digits, found 4"), std::string::npos);
  EXPECT_NE(error_of(std::string(63, 'a') + "g\n").find("character 64"), std::string::npos);
  EXPECT_NE(error_of("").find("found 0"), std::string::npos);
  EXPECT_EQ(error_of("  " + std::string(64, 'A') + "\n\n"), "no error");
  EXPECT_THROW((void)LinkKey::load(dir_ / "missing.key"), LinkKeyError);
}

TEST_F(KeyFiles, SearchOrderIsFlagThenEnvThenUserThenSystem) {
  const fs::path flag = dir_ / "flag.key", env = dir_ / "env.key";
  const fs::path xdg = dir_ / "xdg", home = dir_ / "home";
  LinkKey::generate().save(flag);
  LinkKey::generate().save(env);
  LinkKey::generate().save(xdg / "tsmh" / "link.key");
  LinkKey::generate().save(home / ".config" / "tsmh" / "link.key");
  EXPECT_EQ(find_key_file(flag.string(), env.c_str(), xdg.c_str(), home.c_str()), flag);
  EXPECT_EQ(find_key_file("", env.c_str(), xdg.c_str(), home.c_str()), env);
  EXPECT_EQ(find_key_file("", "", xdg.c_str(), home.c_str()), xdg / "tsmh" / "link.key");
  EXPECT_EQ(find_key_file("", nullptr, nullptr, home.c_str()),
            home / ".config" / "tsmh" / "link.key");
  const auto defaults = default_key_locations(nullptr, home.c_str());
  ASSERT_EQ(defaults.size(), 2U);
  EXPECT_EQ(defaults.back(), fs::path("/etc/tsmh/link.key"));
  if (!fs::exists("/etc/tsmh/link.key")) {
    EXPECT_EQ(find_key_file("", nullptr, nullptr, (dir_ / "nobody").c_str()), std::nullopt);
  }
  // A file named explicitly must exist: a typo never falls back to another key.
  EXPECT_THROW((void)find_key_file((dir_ / "typo.key").string(), env.c_str(), nullptr, nullptr),
               LinkKeyError);
  EXPECT_THROW((void)find_key_file("", (dir_ / "typo.key").c_str(), xdg.c_str(), nullptr),
               LinkKeyError);
}

/// Sets environment variables for one test and restores them.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (old_)
      setenv(name_, old_->c_str(), 1);
    else
      unsetenv(name_);
  }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

TEST_F(KeyFiles, NoKeyRunsOnlyOnHostLocalUrlsOrWithInsecure) {
  if (fs::exists("/etc/tsmh/link.key")) GTEST_SKIP() << "this host has a system-wide key";
  const ScopedEnv no_env(kLinkKeyEnv, "");
  const ScopedEnv xdg("XDG_CONFIG_HOME", (dir_ / "empty").string());
  const std::string network = "udpm://239.255.76.67:7667?ttl=1";
  try {
    (void)resolve_link_security(network, {});
    FAIL() << "ran unauthenticated on a network URL";
  } catch (const LinkKeyError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("tsm-link keygen"), std::string::npos) << what;
    EXPECT_NE(what.find("--insecure"), std::string::npos) << what;
    EXPECT_NE(what.find((dir_ / "empty" / "tsmh" / "link.key").string()), std::string::npos)
        << "says where it looked: " << what;
  }
  EXPECT_THROW((void)resolve_link_security("udpm://239.255.76.67:7667", {}), LinkKeyError)
      << "no explicit ttl=0: not confined";
  for (const std::string& local : {std::string(kDefaultLcmUrl), std::string("memq://"),
                                   std::string("file:///tmp/run.lcmlog")}) {
    const auto s = resolve_link_security(local, {});
    EXPECT_EQ(s.key, nullptr) << local;
    EXPECT_NE(s.notice.find("NOT authenticated"), std::string::npos) << s.notice;
    EXPECT_NE(s.notice.find("confined to this host"), std::string::npos) << s.notice;
  }
  const auto insecure = resolve_link_security(network, {.key_file = "", .insecure = true});
  EXPECT_EQ(insecure.key, nullptr);
  EXPECT_NE(insecure.notice.find("WARNING"), std::string::npos);

  LinkKey::generate().save(dir_ / "empty" / "tsmh" / "link.key");
  const auto keyed = resolve_link_security(network, {.key_file = "", .insecure = true});
  ASSERT_NE(keyed.key, nullptr) << "a key found is always used";
  EXPECT_NE(keyed.notice.find(keyed.key->fingerprint()), std::string::npos) << keyed.notice;
  EXPECT_NE(resolve_link_security(kDefaultLcmUrl, {}).key, nullptr) << "on this host too";
}

// ---- over real udpm -----------------------------------------------------------

/// Records every raw message of one channel (what a rogue on the network sees).
class Tap {
 public:
  Tap(const std::string& url, const std::string& channel) : lcm_(url) {
    lcm_.subscribeFunction<Tap*>(
        channel,
        [](const lcm::ReceiveBuffer* rb, const std::string&, Tap* self) {
          const auto* p = static_cast<const std::uint8_t*>(rb->data);
          const std::lock_guard<std::mutex> lock(self->mutex_);
          self->captured_.emplace_back(p, p + rb->data_size);
        },
        this);
    thread_ = std::thread([this] {
      while (!stop_)
        lcm_.handleTimeout(10);
    });
  }
  ~Tap() {
    stop_ = true;
    thread_.join();
  }
  Tap(const Tap&) = delete;
  Tap& operator=(const Tap&) = delete;
  std::vector<std::vector<std::uint8_t>> captured() {
    const std::lock_guard<std::mutex> lock(mutex_);
    return captured_;
  }

 private:
  lcm::LCM lcm_;
  std::mutex mutex_;
  std::vector<std::vector<std::uint8_t>> captured_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

MasterCommandSample command(std::int64_t seq, double q) {
  MasterCommandSample c;
  c.utime = realtime::monotonic_utime();
  c.seq = seq;
  c.num_joints = 2;
  c.position_ref[0] = q;
  c.position_ref[1] = -q;
  return c;
}

TEST(LinkAuthUdpm, RoguePublishersMoveNothingAuthenticatedPeerDoes) {
  const auto key = new_key();
  const std::string url = test::test_url(), prefix = test::unique_prefix();
  const std::string channel = prefix + "MASTER_COMMAND";
  Receiver rx({.url = url, .prefix = prefix, .key = key});
  auto& in = rx.subscribe<MasterCommandSample>({.expected_joints = 2});
  rx.start();
  Tap tap(url, channel);

  // The authenticated peer: 50 commands to q = 0.1.
  constexpr int kGood = 50;
  {
    Sender peer({.url = url, .prefix = prefix, .key = key});
    auto& out = peer.outbox<MasterCommandSample>();
    peer.start();
    for (int i = 1; i <= kGood; ++i) {
      ASSERT_TRUE(out.publish(command(i, 0.1)));
      std::this_thread::sleep_for(1ms);
    }
  }
  ASSERT_TRUE(wait_until([&] { return in.stats().accepted == kGood; }))
      << "accepted " << in.stats().accepted;
  ASSERT_TRUE(wait_until([&] { return tap.captured().size() == kGood; }));
  const auto captured = tap.captured();  // the authentic messages only
  MasterCommandSample got;
  ASSERT_NE(in.latest(got), 0U);
  EXPECT_EQ(got.seq, kGood);
  EXPECT_EQ(got.position_ref[0], 0.1);

  // Rogues command q = 1.5 with newer seq and utime: valid encodings throughout.
  constexpr int kEach = 40;
  {
    Sender no_key({.url = url, .prefix = prefix});
    Sender wrong_key({.url = url, .prefix = prefix, .key = new_key()});
    auto& a = no_key.outbox<MasterCommandSample>();
    auto& b = wrong_key.outbox<MasterCommandSample>();
    no_key.start();
    wrong_key.start();
    for (int i = 0; i < kEach; ++i) {
      ASSERT_TRUE(a.publish(command(1000 + i, 1.5)));
      ASSERT_TRUE(b.publish(command(2000 + i, 1.5)));
      std::this_thread::sleep_for(1ms);
    }
  }
  // Replayed: the captured authentic messages sent again as they were, then
  // in reverse order; and a recording of another sender run, too old.
  lcm::LCM raw(url);
  for (const auto& m : captured)
    raw.publish(channel, m.data(), static_cast<unsigned>(m.size()));
  for (auto it = captured.rbegin(); it != captured.rend(); ++it)
    raw.publish(channel, it->data(), static_cast<unsigned>(it->size()));
  const MessageSigner old_run(key);
  std::vector<std::uint8_t> payload;
  encode_sample(command(5000, 1.5), payload);
  const auto stale =
      signed_message(old_run, channel, payload, 1, realtime::wall_clock_utime() - 60'000'000);
  raw.publish(channel, stale.data(), static_cast<unsigned>(stale.size()));

  const std::uint64_t expected_rejected = 2 * kEach + 2 * kGood + 1;
  ASSERT_TRUE(wait_until([&] { return in.stats().rejected() == expected_rejected; }))
      << "rejected " << in.stats().rejected();
  std::this_thread::sleep_for(50ms);  // nothing else arrives late
  const ChannelStats st = in.stats();
  EXPECT_EQ(st.accepted, static_cast<std::uint64_t>(kGood)) << "nothing a rogue sent got through";
  EXPECT_EQ(st.rejected(RejectReason::kUnauthenticated), static_cast<std::uint64_t>(kEach));
  EXPECT_EQ(st.rejected(RejectReason::kBadMac), static_cast<std::uint64_t>(kEach));
  EXPECT_EQ(st.rejected(RejectReason::kReplayed), static_cast<std::uint64_t>(2 * kGood));
  EXPECT_EQ(st.rejected(RejectReason::kStale), 1U);
  EXPECT_EQ(st.received, st.accepted + st.dropped());
  ASSERT_NE(in.latest(got), 0U);
  EXPECT_EQ(got.seq, kGood);
  EXPECT_EQ(got.position_ref[0], 0.1) << "the robot still follows the authenticated peer only";
  const auto last = in.last_rejection();
  ASSERT_TRUE(last.has_value());
  EXPECT_NE(describe(*last, channel).find("outside the freshness window"), std::string::npos)
      << describe(*last, channel);

  // And the peer still gets through afterwards (the window was not disturbed).
  Sender peer({.url = url, .prefix = prefix, .key = key});
  auto& out = peer.outbox<MasterCommandSample>();
  peer.start();
  ASSERT_TRUE(out.publish(command(kGood + 1, 0.2)));
  ASSERT_TRUE(wait_until([&] { return in.stats().accepted == kGood + 1; }));
  ASSERT_NE(in.latest(got), 0U);
  EXPECT_EQ(got.position_ref[0], 0.2);
}

TEST(LinkAuthUdpm, UnkeyedReceiverStillDecodesSignedTraffic) {
  // Tools and monitors without the key (lcm-spy decodes the same way) read the payload.
  const std::string url = test::test_url(), prefix = test::unique_prefix();
  Receiver rx({.url = url, .prefix = prefix});
  auto& in = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
  rx.start();
  Sender tx({.url = url, .prefix = prefix, .key = new_key()});
  tx.start();
  ASSERT_EQ(publish_sample(tx.lcm(), prefix + "SLAVE_STATE",
                           make_state(3, realtime::monotonic_utime()), tx.signer()),
            0);
  ASSERT_TRUE(wait_until([&] { return in.stats().accepted == 1; }));
  SlaveStateSample s;
  ASSERT_NE(in.latest(s), 0U);
  EXPECT_EQ(s.seq, 3);
  EXPECT_EQ(s.x_in[1], 0.003 + 1);
}

}  // namespace
}  // namespace tsmh::bridge
