#pragma once
// The LCM channels and how their names are formed: an optional per-arm
// prefix (e.g. "ARM1_") followed by the upper-case base name.

#include <array>
#include <cstddef>
#include <string>
#include <string_view>

namespace tsmh::bridge {

enum class Channel {
  kSlaveState,     ///< slave -> master, per slave tick (1 kHz)
  kSlaveTruth,     ///< virtual slave -> evaluation: true distal torque, friction
  kMasterCommand,  ///< haptic server -> slave, per haptic tick
  kHapticStatus,   ///< haptic server -> monitors, 100 Hz

  kCalibrationRequest,  ///< external console -> haptic server: recalibrate
};

inline constexpr std::array<Channel, 5> kAllChannels = {
    Channel::kSlaveState, Channel::kSlaveTruth, Channel::kMasterCommand, Channel::kHapticStatus,
    Channel::kCalibrationRequest};

/// "SLAVE_STATE", "SLAVE_TRUTH", ...
std::string_view base_name(Channel channel) noexcept;

/// prefix + base name, e.g. channel_name("ARM1_", Channel::kSlaveState) == "ARM1_SLAVE_STATE".
std::string channel_name(std::string_view prefix, Channel channel);

/// LCM refuses longer channel names (LCM_MAX_CHANNEL_NAME_LENGTH).
inline constexpr std::size_t kMaxChannelLength = 63;

/// Throws std::invalid_argument naming the channel when LCM would refuse it
/// (empty or longer than kMaxChannelLength): LCM itself only prints to stderr.
void check_channel_name(std::string_view name);

/// LCM 1.3 subscribes with a regular expression; this escapes a literal
/// channel name so a prefix containing '.', '+', ... matches only itself.
std::string regex_escape(std::string_view literal);

}  // namespace tsmh::bridge
