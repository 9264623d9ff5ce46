// One way an enum value gets its name: a table in declaration order, the
// caller's word for a value outside the enum.
#include <gtest/gtest.h>

#include <cstdint>

#include "realtime/enum_names.hpp"

namespace tsmh::realtime {
namespace {

enum class Light : std::uint8_t { kRed, kAmber, kGreen };
enum class Signed : std::int32_t { kLow = 0, kHigh = 1 };

constexpr std::string_view light_name(Light l) noexcept {
  return enum_name<Light::kGreen>(l, {"red", "amber", "green"}, "dark");
}

TEST(EnumNames, EachValueGetsItsNameInDeclarationOrder) {
  EXPECT_EQ(light_name(Light::kRed), "red");
  EXPECT_EQ(light_name(Light::kAmber), "amber");
  EXPECT_EQ(light_name(Light::kGreen), "green");
  static_assert(light_name(Light::kAmber) == "amber", "usable in constant expressions");
}

TEST(EnumNames, AValueOutsideTheEnumGetsTheUnknownWord) {
  // A byte off the wire or a corrupted value: never read past the table.
  EXPECT_EQ(light_name(static_cast<Light>(3)), "dark");
  EXPECT_EQ(light_name(static_cast<Light>(255)), "dark");
  EXPECT_EQ(enum_name<Signed::kHigh>(static_cast<Signed>(-1), {"low", "high"}), "?");
  EXPECT_EQ(enum_name<Signed::kHigh>(static_cast<Signed>(2), {"low", "high"}), "?");
  EXPECT_EQ(enum_name<Signed::kHigh>(Signed::kHigh, {"low", "high"}), "high");
}

TEST(EnumNames, TheNamesAreNulTerminatedLiterals) {
  // Callers that hand the name to printf-style code use .data().
  EXPECT_STREQ(light_name(Light::kAmber).data(), "amber");
}

}  // namespace
}  // namespace tsmh::realtime
