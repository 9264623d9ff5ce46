#pragma once
// Message authentication on the LCM link (docs/bridge.md, "Authentication").
//
// Every message a keyed Sender publishes is the unchanged LCM encoding
// followed by a 72-byte trailer (version 2):
//
//   offset  0  "TSMA"            magic
//           4  u8 version (2), 3 bytes zero
//           8  u64 sender id     random per Sender (per process start)
//          16  u64 sequence      per Sender, +1 per message on any channel
//          24  i64 send time     CLOCK_REALTIME, microseconds
//          32  u64 peer id       the sender id of the peer session this sender
//                                is bound to (or answers in a handshake), 0 = none
//                                (bridge/link_session.hpp)
//          40  32-byte MAC       HMAC-SHA-512-256 (libsodium crypto_auth) over
//                                channel name, 0x00, payload, trailer bytes 0..39
//
// Version 1 (64 bytes: no peer id, MAC at offset 32) is what programs wrote
// before sessions; it is still verified in stored logs (verify_stored) and
// refused by live receivers.
//
// LCM decoders (C++ lcm-gen decode, Java's LCMDataInputStream, hence
// lcm-spy) read the fields they know and ignore what follows, and
// lcm-logger stores the bytes as they came, so the tools keep working. A
// keyed Receiver accepts a message only with a valid MAC, a send time within
// max_age of its own clock, and a (sender id, sequence) it has not seen
// (a sliding 1024-bit window per sender). The key is 32 random bytes shared
// by the peers of one installation (`tsm-link keygen`).

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace tsmh::bridge {

inline constexpr std::size_t kLinkKeyBytes = 32;
/// The trailer every keyed Sender writes (version 2).
inline constexpr std::size_t kAuthTrailerBytes = 72;
/// The trailer of version 1 (logs recorded before sessions).
inline constexpr std::size_t kAuthTrailerV1Bytes = 64;
inline constexpr std::size_t kAuthMacBytes = 32;

/// A key file that is missing, unreadable, malformed or too permissive;
/// what() names the file and the fix.
class LinkKeyError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The shared secret. Wiped from memory when destroyed.
class LinkKey {
 public:
  /// 32 bytes from the OS random source (libsodium randombytes_buf).
  static LinkKey generate();
  /// 64 hex digits (surrounding whitespace ignored); `where` names the source in errors.
  static LinkKey from_hex(std::string_view text, std::string_view where);
  /// Reads a key file. Refuses files that group or others may read or write
  /// (the mode must be 0600 or stricter) and anything but 64 hex digits.
  static LinkKey load(const std::filesystem::path& file);

  LinkKey(const LinkKey&) = default;
  LinkKey& operator=(const LinkKey&) = default;
  ~LinkKey();

  /// Writes the key as 64 hex digits + newline to a new file created with
  /// mode 0600 (missing parent folders are created). Refuses to overwrite unless `overwrite`.
  void save(const std::filesystem::path& file, bool overwrite = false) const;

  const std::array<std::uint8_t, kLinkKeyBytes>& bytes() const noexcept { return bytes_; }
  /// 16 hex digits of a hash of the key: tells peers whether they share a key
  /// without revealing it.
  std::string fingerprint() const;

 private:
  LinkKey() = default;
  std::array<std::uint8_t, kLinkKeyBytes> bytes_{};
};

/// The decoded trailer of a message. (peer_id last: aggregate initialisers
/// written for version 1 keep their meaning, with peer 0.)
struct AuthTrailer {
  std::uint64_t sender_id = 0;
  std::uint64_t seq = 0;
  std::int64_t send_time_us = 0;
  std::uint64_t peer_id = 0;  ///< version 2 only; 0 = not bound to a peer
  std::uint8_t version = 2;   ///< as read (1 or 2); sign_as always writes 2
};

/// The size of the trailer `data` ends with, by its magic and version:
/// kAuthTrailerBytes (version 2), kAuthTrailerV1Bytes (version 1) or 0 (none).
/// The payload is the first size - auth_trailer_size() bytes.
std::size_t auth_trailer_size(const std::uint8_t* data, std::size_t size) noexcept;
/// auth_trailer_size() != 0.
bool has_auth_trailer(const std::uint8_t* data, std::size_t size) noexcept;

/// Signs messages of one Sender. sign() and sign_at() are thread-safe and
/// async-signal-safe: lock-free atomics, clock_gettime and the HMAC over
/// caller-owned memory; no allocation, no lock.
class MessageSigner {
 public:
  explicit MessageSigner(std::shared_ptr<const LinkKey> key);
  /// Writes the trailer for `payload` published on `channel` to
  /// trailer[0..kAuthTrailerBytes): the next sequence, CLOCK_REALTIME now and
  /// the current peer id. No allocation.
  void sign(std::string_view channel, const std::uint8_t* payload, std::size_t size,
            std::uint8_t* trailer) noexcept;
  /// Same with a given sequence and send time, this signer's id and the
  /// current peer id (a prepared message signed at the last moment).
  void sign_at(std::string_view channel, const std::uint8_t* payload, std::size_t size,
               std::uint64_t seq, std::int64_t send_time_us, std::uint8_t* trailer) const noexcept;
  /// Same with every field given (t.version is ignored: version 2 is written).
  void sign_as(std::string_view channel, const std::uint8_t* payload, std::size_t size,
               const AuthTrailer& t, std::uint8_t* trailer) const noexcept;
  std::uint64_t sender_id() const noexcept { return sender_id_; }
  /// Takes `count` sequence numbers for messages signed with sign_at(); returns the first.
  std::uint64_t reserve_seq(std::uint64_t count = 1) noexcept {
    return next_seq_.fetch_add(count, std::memory_order_relaxed);
  }

  /// The peer id written into every following trailer (0 = none). Set by the
  /// link's Session (bridge/link_session.hpp) from the receive thread.
  void set_peer_id(std::uint64_t peer) noexcept { peer_id_.store(peer, std::memory_order_release); }
  std::uint64_t peer_id() const noexcept { return peer_id_.load(std::memory_order_acquire); }

 private:
  std::shared_ptr<const LinkKey> key_;
  std::uint64_t sender_id_;
  std::atomic<std::uint64_t> next_seq_{1};
  std::atomic<std::uint64_t> peer_id_{0};
};

enum class AuthVerdict : std::uint8_t {
  kOk,
  kMissing,   ///< no trailer: an unauthenticated sender
  kVersion1,  ///< a version 1 trailer (no peer id): a program from before sessions
  kBadMac,    ///< wrong key, or bytes altered on the way
  kStale,     ///< send time further than max_age from the receiver's clock
  kReplayed,  ///< (sender id, sequence) already seen, or older than the window
};

struct AuthResult {
  AuthVerdict verdict = AuthVerdict::kMissing;
  std::size_t payload_size = 0;  ///< valid when verdict is Ok
  AuthTrailer trailer{};         ///< decoded when a trailer was present
  std::int64_t age_us = 0;       ///< receiver clock - send time (Stale)
};

struct VerifierOptions {
  /// Largest |receiver CLOCK_REALTIME - send time| accepted. Bounds how long
  /// a recorded message can be replayed to a receiver that has not seen its
  /// sender; across hosts the clocks must agree to well within it (NTP).
  std::int64_t max_age_us = 2'000'000;
  /// false: no freshness check (a receiver reading a log: file://).
  bool check_freshness = true;
  /// Accept version 1 trailers (logs recorded before sessions; file://). A
  /// live receiver refuses them: they name no peer, so no session can hold.
  bool accept_version_1 = false;
};

/// Verifies messages for one receive thread (not thread-safe; no allocation
/// after construction). Keeps a replay window for up to kSenders senders;
/// the least recently heard is forgotten when a new one appears.
class MessageVerifier {
 public:
  static constexpr std::size_t kSenders = 32;
  static constexpr std::uint64_t kWindow = 1024;  ///< sequence numbers remembered per sender

  explicit MessageVerifier(std::shared_ptr<const LinkKey> key, VerifierOptions options = {});
  /// Checks trailer, MAC, freshness (against `now_realtime_us`) and replay, in
  /// that order; only a message that passes all of them enters the window.
  AuthResult verify(std::string_view channel, const std::uint8_t* data, std::size_t size,
                    std::int64_t now_realtime_us) noexcept;
  const VerifierOptions& options() const noexcept { return options_; }

 private:
  struct Window {
    std::uint64_t sender_id = 0;
    std::uint64_t top = 0;        // highest sequence accepted
    std::uint64_t last_used = 0;  // for least-recently-used replacement
    bool used = false;
    std::array<std::uint64_t, kWindow / 64> seen{};  // bit (seq % kWindow)
  };
  Window* find(std::uint64_t sender_id) noexcept;
  Window& claim(std::uint64_t sender_id) noexcept;

  std::shared_ptr<const LinkKey> key_;
  VerifierOptions options_;
  std::array<Window, kSenders> windows_{};
  std::uint64_t uses_ = 0;
};

/// Verifies one stored message (a log) with `key`, without freshness or
/// replay checks: Ok, Missing or BadMac. Version 1 and 2 trailers.
AuthVerdict verify_stored(const LinkKey& key, std::string_view channel, const std::uint8_t* data,
                          std::size_t size) noexcept;

}  // namespace tsmh::bridge
