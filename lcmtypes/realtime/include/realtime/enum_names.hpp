#pragma once
// The one way an enum value gets its name (a status word, a reason, a
// channel): a table of names in the enum's declaration order, looked up by
// the value. Every enum-to-text function of the project is one call to
// enum_name(); a value outside the enum (a corrupted byte, a number read off
// the wire) gets the caller's `unknown` word instead of reading past the table.
//
// Where a switch would warn about a value added to the enum without a name,
// the table is checked at compile time against the enum's last value: it must
// hold exactly one name per value 0..Last. Such enums keep their values
// 0, 1, 2, ... in declaration order and name their last value in the call.

#include <cstddef>
#include <string_view>
#include <type_traits>

namespace tsmh::realtime {

/// The name of `value`: names[value] for an enum whose values run 0..Last in
/// declaration order, `unknown` for any other value. No allocation, no throw:
/// callable from the real-time loop.
///   std::string_view to_string(LoopState s) noexcept {
///     return realtime::enum_name<LoopState::kFault>(s, {"DISABLED", "ENABLED", "FAULT"});
///   }
template <auto Last, std::size_t N>
constexpr std::string_view enum_name(decltype(Last) value, const std::string_view (&names)[N],
                                     std::string_view unknown = "?") noexcept {
  using Enum = decltype(Last);
  static_assert(std::is_enum_v<Enum>, "enum_name<Last>: Last is the enum's last value");
  static_assert(static_cast<std::size_t>(Last) + 1 == N,
                "enum_name: one name per enum value 0..Last, in declaration order");
  // A negative value of a signed enum becomes a huge index: unknown.
  const auto index = static_cast<std::size_t>(static_cast<std::underlying_type_t<Enum>>(value));
  return index < N ? names[index] : unknown;
}

}  // namespace tsmh::realtime
