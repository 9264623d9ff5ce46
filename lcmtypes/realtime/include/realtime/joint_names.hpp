#pragma once
// The one name a user sees for each joint: "joint1", "joint2", ... (1-based,
// as the paper's Joint1/Joint2 and haptic-server's default joint names).
// Every message, help text, plot and report names a joint this way; arrays,
// messages and trace columns stay 0-based (realtime/joints.hpp).

#include <charconv>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>

namespace tsmh::realtime {

/// The name a user sees for the joint at 0-based `index`: "joint1",
/// "joint2", ... (1-based, as the paper's Joint1/Joint2 and haptic-server's
/// default joint names). Every message, help text, plot and report names a
/// joint this way; arrays, messages and trace columns stay 0-based.
inline std::string joint_name(std::size_t index) {
  return "joint" + std::to_string(index + 1);
}

/// The 0-based index of the joint a user named on a command line: its name
/// ("joint2"), or, as earlier versions took it, its 0-based index ("1").
/// nullopt when that is no joint below `count`.
inline std::optional<std::size_t> joint_from_text(std::string_view text, std::size_t count) {
  const bool named = text.substr(0, 5) == "joint";
  if (named) text.remove_prefix(5);
  std::size_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  if (named) {
    if (v < 1) return std::nullopt;
    --v;
  }
  return v < count ? std::optional<std::size_t>(v) : std::nullopt;
}

}  // namespace tsmh::realtime
