#include "bridge/channels.hpp"

#include <lcm/lcm.h>

#include <stdexcept>

#include "realtime/enum_names.hpp"

static_assert(tsmh::bridge::kMaxChannelLength == LCM_MAX_CHANNEL_NAME_LENGTH);

namespace tsmh::bridge {

std::string_view base_name(Channel channel) noexcept {
  return realtime::enum_name<Channel::kCalibrationRequest>(
      channel,
      {"SLAVE_STATE", "SLAVE_TRUTH", "MASTER_COMMAND", "HAPTIC_STATUS", "CALIBRATION_REQUEST"},
      "UNKNOWN");
}

std::string channel_name(std::string_view prefix, Channel channel) {
  std::string name(prefix);
  name += base_name(channel);
  return name;
}

void check_channel_name(std::string_view name) {
  if (name.empty()) throw std::invalid_argument("LCM channel name is empty");
  if (name.size() > kMaxChannelLength) {
    std::string msg = "LCM channel name '";
    msg += name;
    msg += "' has ";
    msg += std::to_string(name.size());
    msg += " characters; LCM allows at most ";
    msg += std::to_string(kMaxChannelLength);
    msg += " (shorten the prefix)";
    throw std::invalid_argument(msg);
  }
}

std::string regex_escape(std::string_view literal) {
  static constexpr std::string_view kSpecial = R"(\^$.|?*+()[]{})";
  std::string out;
  out.reserve(literal.size() * 2);
  for (char c : literal) {
    if (kSpecial.find(c) != std::string_view::npos) out += '\\';
    out += c;
  }
  return out;
}

}  // namespace tsmh::bridge
