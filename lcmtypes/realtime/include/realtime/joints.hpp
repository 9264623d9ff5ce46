#pragma once
// The joint count a build handles, and the fixed-size per-joint array the
// real-time code passes around (fixed so that nothing allocates). One
// definition for the messages (bridge: a message with more joints is
// rejected), the master devices (their DOF) and the loop, which uses one
// JointArray for both.

#include <array>
#include <cstddef>

namespace tsmh::realtime {

/// Upper bound on the joints of anything this build drives: a master of up
/// to 7 DOF plus a grip; a NOTES arm has 2-4 actuated joints per instrument.
inline constexpr std::size_t kMaxJoints = 8;

/// One value per joint; entries at and beyond the joint count are zero.
using JointArray = std::array<double, kMaxJoints>;

}  // namespace tsmh::realtime
