#pragma once
// Why an incoming message was dropped before reaching the loop, in a fixed-size
// form the receive thread can record without allocating.

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace tsmh::bridge {

enum class RejectReason : std::uint8_t {
  kDecode,         ///< truncated, oversized, garbage bytes or another message type
  kJointCount,     ///< num_joints outside 1..kMaxJoints or not the configured count
  kNonFinite,      ///< NaN or Inf where a number is required
  kOutOfRange,     ///< outside the configured Range
  kTimeBackwards,  ///< utime not after the last accepted one although seq advanced
  kImplausible,    ///< a step from the last accepted sample faster than the hardware can move
  // Authentication (keyed Receiver only; bridge/link_auth.hpp), checked first:
  kUnauthenticated,  ///< no MAC trailer: a sender without the link key
  kBadMac,           ///< MAC does not match: wrong key, or bytes altered
  kStale,            ///< send time too far from the receiver's clock (an old recording)
  kReplayed,         ///< (sender id, sequence) already seen or older than the replay window
  // Sessions (keyed session channels only; bridge/link_session.hpp), after authentication:
  kOtherSession,  ///< a keyed sender that is not this session's peer: ends the session in FAULT
  kSessionEnded,  ///< the session is closed or in FAULT: nothing is used any more
};
inline constexpr int kRejectReasons = 12;

/// "decode", "joint_count", "non_finite", "out_of_range", "time_backwards",
/// "implausible_step", "unauthenticated", "bad_mac", "stale", "replayed",
/// "other_session", "session_ended".
std::string_view reason_name(RejectReason reason) noexcept;

struct Rejection {
  RejectReason reason = RejectReason::kDecode;
  std::int32_t joint = -1;      ///< joint index at fault, -1 when not joint-specific
  double value = 0;             ///< the offending value (field value, joint count, byte count)
  std::int64_t seq = -1;        ///< the message's seq when it could be read, else -1
  std::int64_t receive_ns = 0;  ///< receiver's CLOCK_MONOTONIC when it arrived
  std::array<char, 64> what{};  ///< field name ("x_in") or decode detail, NUL-terminated
};

/// Builds a rejection; `what` is truncated to fit.
Rejection make_rejection(RejectReason reason, std::string_view what, double value = 0,
                         std::int32_t joint = -1) noexcept;

/// Human-readable, names the channel, field and joint, e.g.
/// "ARM1_SLAVE_STATE seq 42: x_in[1] = nan is not finite".
std::string describe(const Rejection& r, std::string_view channel);

}  // namespace tsmh::bridge
