#pragma once
// Conversion between the fixed-size samples and the lcm-gen message classes,
// and the samples' decoder: lcmtypes' MessageDecoder (which checks the raw
// bytes before lcm-gen's decode() may size anything) turned into samples and
// the bridge's rejections.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <tsmh/calibration_request_t.hpp>
#include <tsmh/haptic_status_t.hpp>
#include <tsmh/master_command_t.hpp>
#include <tsmh/slave_state_t.hpp>
#include <tsmh/slave_truth_t.hpp>
#include <utility>
#include <vector>

#include "bridge/channels.hpp"
#include "bridge/limits.hpp"
#include "bridge/rejection.hpp"
#include "bridge/samples.hpp"
#include "lcmtypes/message_decoder.hpp"

namespace lcm {
class LCM;
}

namespace tsmh::bridge {

class MessageSigner;  // bridge/link_auth.hpp

/// Which message, channel and limits belong to a sample type.
template <class Sample>
struct SampleTraits;

/// One sample type's message, limits and channel, the parts of its SampleTraits.
template <class MessageT, class LimitsT, Channel kChannel>
struct SampleTraitsOf {
  using Message = MessageT;
  using Limits = LimitsT;
  static constexpr Channel channel = kChannel;
};

template <>
struct SampleTraits<SlaveStateSample>
    : SampleTraitsOf<tsmh::slave_state_t, SlaveStateLimits, Channel::kSlaveState> {};
template <>
struct SampleTraits<SlaveTruthSample>
    : SampleTraitsOf<tsmh::slave_truth_t, SlaveTruthLimits, Channel::kSlaveTruth> {};
template <>
struct SampleTraits<MasterCommandSample>
    : SampleTraitsOf<tsmh::master_command_t, MasterCommandLimits, Channel::kMasterCommand> {};
template <>
struct SampleTraits<HapticStatusSample>
    : SampleTraitsOf<tsmh::haptic_status_t, HapticStatusLimits, Channel::kHapticStatus> {};
template <>
struct SampleTraits<CalibrationRequestSample>
    : SampleTraitsOf<tsmh::calibration_request_t, CalibrationRequestLimits,
                     Channel::kCalibrationRequest> {};

/// The channel a Sample travels on: `given` when it is not empty, else
/// prefix + its base name (channel_name).
template <class Sample>
std::string sample_channel(std::string_view prefix, std::string given) {
  return given.empty() ? channel_name(prefix, SampleTraits<Sample>::channel) : std::move(given);
}

// Sample -> message (copies num_joints entries of each array; receive_ns is not sent).
void to_message(const SlaveStateSample& s, tsmh::slave_state_t& m);
void to_message(const SlaveTruthSample& s, tsmh::slave_truth_t& m);
void to_message(const MasterCommandSample& s, tsmh::master_command_t& m);
void to_message(const HapticStatusSample& s, tsmh::haptic_status_t& m);
void to_message(const CalibrationRequestSample& s, tsmh::calibration_request_t& m);

// Message -> sample. Precondition: 0 <= m.num_joints <= kMaxJoints and the
// arrays hold num_joints entries (MessageDecoder guarantees it). receive_ns is left as is.
void from_message(const tsmh::slave_state_t& m, SlaveStateSample& s) noexcept;
void from_message(const tsmh::slave_truth_t& m, SlaveTruthSample& s) noexcept;
void from_message(const tsmh::master_command_t& m, MasterCommandSample& s) noexcept;
void from_message(const tsmh::haptic_status_t& m, HapticStatusSample& s) noexcept;
void from_message(const tsmh::calibration_request_t& m, CalibrationRequestSample& s) noexcept;

/// Decodes untrusted bytes into a sample through the project's one message
/// decoder (lcmtypes/message_decoder.hpp: size, type hash, joint count in
/// 1..kMaxJoints and exact encoded size checked from the raw bytes before
/// anything is allocated), reusing its message so that steady-state decoding
/// does not allocate. Content (NaN, ranges) is validate()'s job.
template <class Sample>
class Decoder {
 public:
  using Message = typename SampleTraits<Sample>::Message;

  /// On failure returns the rejection (reason Decode or JointCount) and
  /// leaves `out` unspecified; on success fills `out` (receive_ns untouched).
  std::optional<Rejection> decode(const void* data, std::size_t size, Sample& out) noexcept;

 private:
  lcmtypes::MessageDecoder<Message> decoder_{{1, kMaxJoints}};
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
