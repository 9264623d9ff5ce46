#pragma once
// Message authentication on the LCM link (docs/bridge.md, "Authentication").
//
// Every message a keyed Sender publishes is the unchanged LCM encoding
// followed by a 64-byte trailer:
//
//   offset  0  "TSMA"            magic
//           4  u8 version (1), 3 bytes zero
//           8  u64 sender id     random per Sender (per process start)
//          16  u64 sequence      per Sender, +1 per message on any channel
//          24  i64 send time     CLOCK_REALTIME, microseconds
//          32  32-byte MAC       HMAC-SHA-512-256 (libsodium crypto_auth) over
//                                channel name, 0x00, payload, trailer bytes 0..31
//
// LCM decoders (C++ lcm-gen decode, Java's LCMDataInputStream, hence
// lcm-spy) read the fields they know and ignore what follows, and
// lcm-logger stores the bytes as they came, so the tools keep working. A
// keyed Receiver accepts a message only with a valid MAC, a send time within
// max_age of its own clock, and a (sender id, sequence) it has not seen
// (a sliding 1024-bit window per sender). The key is 32 random bytes shared
// by the peers of one installation (`tsm keygen`).

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
inline constexpr std::size_t kAuthTrailerBytes = 64;
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

/// The decoded trailer of a message.
struct AuthTrailer {
  std::uint64_t sender_id = 0;
  std::uint64_t seq = 0;
  std::int64_t send_time_us = 0;
};

/// Whether `data` ends with a trailer (by its magic and version); such a
/// message's payload is the first size - kAuthTrailerBytes bytes.
bool has_auth_trailer(const std::uint8_t* data, std::size_t size) noexcept;

/// Signs messages of one Sender. sign() is thread-safe (the sequence is atomic).
class MessageSigner {
 public:
  explicit MessageSigner(std::shared_ptr<const LinkKey> key);
  /// Writes the trailer for `payload` published on `channel` to
  /// trailer[0..kAuthTrailerBytes). No allocation.
  void sign(std::string_view channel, const std::uint8_t* payload, std::size_t size,
            std::uint8_t* trailer) noexcept;
  /// Same with a given sequence and send time (tests and benchmarks).
  void sign_as(std::string_view channel, const std::uint8_t* payload, std::size_t size,
               const AuthTrailer& t, std::uint8_t* trailer) const noexcept;
  std::uint64_t sender_id() const noexcept { return sender_id_; }

 private:
  std::shared_ptr<const LinkKey> key_;
  std::uint64_t sender_id_;
  std::atomic<std::uint64_t> next_seq_{1};
};

enum class AuthVerdict : std::uint8_t {
  kOk,
  kMissing,   ///< no trailer: an unauthenticated sender
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

/// CLOCK_REALTIME in microseconds (the trailer's send time).
std::int64_t realtime_now_us() noexcept;

/// Verifies one stored message (a log) with `key`, without freshness or
/// replay checks: Ok, Missing or BadMac.
AuthVerdict verify_stored(const LinkKey& key, std::string_view channel, const std::uint8_t* data,
                          std::size_t size) noexcept;

}  // namespace tsmh::bridge
