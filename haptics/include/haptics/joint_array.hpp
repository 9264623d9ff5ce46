#pragma once
// Per-joint values in the loop: fixed size so that nothing allocates. The
// joint count is the bridge's (what the messages carry); the master device
// must be able to hold as many.

#include <array>

#include "bridge/samples.hpp"
#include "master_devices/types.hpp"

namespace tsmh::haptics {

using bridge::JointArray;
using bridge::kMaxJoints;
static_assert(master_devices::kMaxDof == static_cast<std::size_t>(kMaxJoints),
              "the master device's joint arrays and the messages' must have one size");

}  // namespace tsmh::haptics
