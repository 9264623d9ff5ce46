#pragma once
// The one way our programs turn received bytes into a message of ours.
//
// lcm-gen's decode() resizes every array to whatever num_joints the bytes
// claim before it looks at how many bytes there are: one datagram claiming
// 2^28 joints makes it allocate gigabytes. MessageDecoder reads the header
// from the raw bytes first -- type hash, num_joints against the caller's
// range, the exact encoded size for that many joints -- and only then lets
// lcm-gen decode, into a message it keeps, whose arrays were sized for the
// largest accepted count at construction: decoding never allocates.
//
// Every message of ours leads with int64 utime, int64 seq, int32 num_joints
// (after LCM's 8-byte type hash), and num_joints is the only array length
// (docs/lcm-messages.md); the size of a message is therefore
// fixed + per_joint * num_joints, which the decoder learns from lcm-gen once.

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

namespace tsmh::lcmtypes {

/// The fields every message of ours starts with, read from raw bytes.
struct WireHeader {
  std::int64_t hash = 0;
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  std::int32_t num_joints = 0;
};
inline constexpr std::size_t kWireHeaderBytes = 8 + 8 + 8 + 4;

/// Reads the leading hash, utime, seq and num_joints (big-endian, as LCM
/// encodes them). False when fewer than kWireHeaderBytes bytes.
bool read_header(const void* data, std::size_t size, WireHeader& out) noexcept;

/// Why bytes were refused, in the order the decoder checks.
enum class DecodeFault : std::uint8_t {
  kTruncatedHeader,  ///< fewer bytes than hash, utime, seq and num_joints
  kTypeHash,         ///< another message type, or garbage
  kJointCount,       ///< num_joints outside the decoder's range
  kSize,             ///< not the exact encoded size for num_joints (cut short, or bytes after it)
  kMalformed,        ///< lcm-gen's decode refused bytes that passed every check above
};

/// "truncated_header", "type_hash", "joint_count", "size", "malformed".
std::string_view fault_name(DecodeFault fault) noexcept;

/// A refusal, fixed-size so a receive thread can keep it without allocating.
struct DecodeError {
  DecodeFault fault = DecodeFault::kMalformed;
  std::int64_t seq = -1;         ///< the header's seq when it could be read, else -1
  std::int32_t num_joints = -1;  ///< the header's num_joints when it could be read
  std::size_t size = 0;          ///< bytes received
  std::size_t expected = 0;      ///< kSize: the exact size for num_joints
  std::array<char, 96> what{};   ///< NUL-terminated, e.g. "num_joints 268435456, expected 2"
};

/// The joint counts a decoder accepts (inclusive).
struct JointRange {
  std::int32_t min = 1;
  std::int32_t max = 1;
};

/// What bytes after the message are. kReject: an error (kSize), the rule
/// for every payload whose length the link fixes (after an authentication
/// trailer is removed). kIgnore: left unread, as every LCM tool does, for a
/// receiver without the link key that may see another peer's trailer.
enum class Trailing : bool { kReject, kIgnore };

/// Decodes untrusted bytes into one message type (the seven of
/// lcmtypes/*.lcm are instantiated). Not thread-safe: one per receiving thread.
template <class Message>
class MessageDecoder {
 public:
  /// The widest range a decoder takes: it sizes its message for `max`.
  static constexpr std::int32_t kMaxJointLimit = 4096;

  /// Throws std::invalid_argument unless 0 <= min <= max <= kMaxJointLimit.
  /// Allocates the message's arrays for `max` joints, once.
  explicit MessageDecoder(JointRange joints);

  /// Checks, in order: header present, type hash, num_joints in range, size
  /// exactly the encoded size for it (or at least it, with Trailing::kIgnore),
  /// then decodes into message(). On failure message() is unspecified.
  /// Never allocates, never throws.
  std::optional<DecodeError> decode(const void* data, std::size_t size,
                                    Trailing trailing = Trailing::kReject) noexcept;

  /// The last successfully decoded message (valid until the next decode()).
  const Message& message() const noexcept { return msg_; }

  /// The exact encoded size (with the type hash) of a message of `num_joints` joints.
  std::size_t encoded_size(std::int32_t num_joints) const noexcept {
    return fixed_bytes_ + per_joint_bytes_ * static_cast<std::size_t>(num_joints);
  }
  JointRange joints() const noexcept { return joints_; }

 private:
  JointRange joints_;
  std::size_t fixed_bytes_ = 0;
  std::size_t per_joint_bytes_ = 0;
  Message msg_{};
};

}  // namespace tsmh::lcmtypes
