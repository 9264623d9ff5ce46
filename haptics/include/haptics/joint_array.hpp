#pragma once
// Per-joint values in the loop: fixed size so that nothing allocates. The
// messages, the master devices and the loop share one joint count and one
// array type (realtime/joints.hpp).

#include "realtime/joints.hpp"

namespace tsmh::haptics {

using realtime::JointArray;
using realtime::kMaxJoints;

}  // namespace tsmh::haptics
