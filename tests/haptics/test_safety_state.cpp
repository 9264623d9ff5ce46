// The loop's state machine: enable, disable and fault transitions.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "haptics/safety_state.hpp"

namespace tsmh::haptics {
namespace {

TEST(SafetyState, Transitions) {
  SafetyStateMachine m;
  SafetyInputs in{.dead_man = false, .device_ok = true};
  EXPECT_EQ(m.update(in), LoopState::kDisabled);
  in.dead_man = true;
  EXPECT_EQ(m.update(in), LoopState::kEnabled);
  in.dead_man = false;
  EXPECT_EQ(m.update(in), LoopState::kDisabled);
  in.dead_man = true;
  m.update(in);
  in.e_stop = true;
  EXPECT_EQ(m.update(in), LoopState::kFault);
  EXPECT_EQ(m.fault(), FaultReason::kEStop);
  in.e_stop = false;
  EXPECT_EQ(m.update(in), LoopState::kFault) << "latched while the dead-man is still held";
  in.dead_man = false;
  EXPECT_EQ(m.update(in), LoopState::kDisabled);
  in.device_ok = false;
  EXPECT_EQ(m.update(in), LoopState::kFault);
  EXPECT_EQ(m.fault(), FaultReason::kDevice);
  in.device_ok = true;
  in.slave_lost = true;
  EXPECT_EQ(m.update(in), LoopState::kFault);
  EXPECT_EQ(m.fault(), FaultReason::kDevice) << "the first cause is kept";
}

}  // namespace
}  // namespace tsmh::haptics
