#pragma once
// Conversion between the fixed-size samples and the lcm-gen message classes,
// and a decoder that does not trust its input. lcm-gen's decode() resizes its
// vectors to whatever num_joints the bytes claim, so a hostile or corrupt
// message (num_joints = -1 or 2^31-1) would throw or exhaust memory: Decoder
// checks length, type hash and joint count from the raw header first.
//
// Every message of ours leads with int64 utime, int64 seq, int32 num_joints
// (after LCM's 8-byte type hash); docs/lcm-messages.md states this invariant
// and tests/bridge checks it for all six types.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <tsmh/calibration_request_t.hpp>
#include <tsmh/haptic_status_t.hpp>
#include <tsmh/master_command_t.hpp>
#include <tsmh/slave_state_t.hpp>
#include <tsmh/slave_truth_t.hpp>
#include <vector>

#include "bridge/channels.hpp"
#include "bridge/limits.hpp"
#include "bridge/rejection.hpp"
#include "bridge/samples.hpp"

namespace lcm {
class LCM;
}

namespace tsmh::bridge {

class MessageSigner;  // bridge/link_auth.hpp

/// Which message, channel and limits belong to a sample type.
template <class Sample>
struct SampleTraits;

template <>
struct SampleTraits<SlaveStateSample> {
  using Message = tsmh::slave_state_t;
  using Limits = SlaveStateLimits;
  static constexpr Channel channel = Channel::kSlaveState;
};
template <>
struct SampleTraits<SlaveTruthSample> {
  using Message = tsmh::slave_truth_t;
  using Limits = SlaveTruthLimits;
  static constexpr Channel channel = Channel::kSlaveTruth;
};
template <>
struct SampleTraits<MasterCommandSample> {
  using Message = tsmh::master_command_t;
  using Limits = MasterCommandLimits;
  static constexpr Channel channel = Channel::kMasterCommand;
};
template <>
struct SampleTraits<HapticStatusSample> {
  using Message = tsmh::haptic_status_t;
  using Limits = HapticStatusLimits;
  static constexpr Channel channel = Channel::kHapticStatus;
};
template <>
struct SampleTraits<CalibrationRequestSample> {
  using Message = tsmh::calibration_request_t;
  using Limits = CalibrationRequestLimits;
  static constexpr Channel channel = Channel::kCalibrationRequest;
};

// Sample -> message (copies num_joints entries of each array; receive_ns is not sent).
void to_message(const SlaveStateSample& s, tsmh::slave_state_t& m);
void to_message(const SlaveTruthSample& s, tsmh::slave_truth_t& m);
void to_message(const MasterCommandSample& s, tsmh::master_command_t& m);
void to_message(const HapticStatusSample& s, tsmh::haptic_status_t& m);
void to_message(const CalibrationRequestSample& s, tsmh::calibration_request_t& m);

// Message -> sample. Precondition: 0 <= m.num_joints <= kMaxJoints and the
// arrays hold num_joints entries (Decoder guarantees it). receive_ns is left as is.
void from_message(const tsmh::slave_state_t& m, SlaveStateSample& s) noexcept;
void from_message(const tsmh::slave_truth_t& m, SlaveTruthSample& s) noexcept;
void from_message(const tsmh::master_command_t& m, MasterCommandSample& s) noexcept;
void from_message(const tsmh::haptic_status_t& m, HapticStatusSample& s) noexcept;
void from_message(const tsmh::calibration_request_t& m, CalibrationRequestSample& s) noexcept;

/// The fields every message of ours starts with, read from raw bytes.
struct RawHeader {
  std::int64_t hash = 0;
  std::int64_t utime = 0;
  std::int64_t seq = 0;
  std::int32_t num_joints = 0;
};
inline constexpr std::size_t kRawHeaderBytes = 8 + 8 + 8 + 4;

/// Reads the leading hash, utime, seq and num_joints (big-endian, as LCM
/// encodes them). False when fewer than kRawHeaderBytes bytes.
bool peek_header(const void* data, std::size_t size, RawHeader& out) noexcept;

/// Decodes untrusted bytes into a sample, reusing its message object so that
/// steady-state decoding does not allocate. Checks, in order: size, type
/// hash, joint count in 1..kMaxJoints, exact encoded size, then decodes.
/// Content (NaN, ranges) is validate()'s job.
template <class Sample>
class Decoder {
 public:
  using Message = typename SampleTraits<Sample>::Message;

  /// On failure returns the rejection (reason Decode or JointCount) and
  /// leaves `out` unspecified; on success fills `out` (receive_ns untouched).
  std::optional<Rejection> decode(const void* data, std::size_t size, Sample& out) noexcept;

 private:
  Message msg_{};
};

/// Encodes a sample into `bytes` (resized to the encoded size). Allocates:
/// not for the real-time loop (use an Outbox there).
template <class Sample>
void encode_sample(const Sample& s, std::vector<std::uint8_t>& bytes);

/// Encodes and publishes synchronously on `lcm`, followed by an
/// authentication trailer when `signer` is set (Sender::signer()). Returns
/// LCM's result (0 on success). Blocking system call: for tools, tests and
/// non-real-time code.
template <class Sample>
int publish_sample(lcm::LCM& lcm, const std::string& channel, const Sample& s,
                   MessageSigner* signer = nullptr);

}  // namespace tsmh::bridge
