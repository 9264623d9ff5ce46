#pragma once
// Per-joint values in the loop: fixed size so that nothing allocates.

#include <array>

namespace tsmh::haptics {

inline constexpr int kMaxJoints = 8;
using JointArray = std::array<double, kMaxJoints>;

}  // namespace tsmh::haptics
