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

TEST(SafetyState, AnotherSessionEndsItWhateverCameFirstAndNeverClears) {
  SafetyStateMachine m;
  SafetyInputs in;
  in.device_ok = true;
  in.dead_man = true;
  m.update(in);
  in.slave_lost = true;
  EXPECT_EQ(m.update(in), LoopState::kFault);
  EXPECT_EQ(m.fault(), FaultReason::kSlaveLost);
  in.slave_session_over = true;
  EXPECT_EQ(m.update(in), LoopState::kFault);
  EXPECT_EQ(m.fault(), FaultReason::kSlaveSession) << "the end of the session is what counts";
  in.slave_lost = false;
  in.dead_man = false;
  EXPECT_EQ(m.update(in), LoopState::kFault) << "no re-arm: the session is over";
  SafetyStateMachine master;
  in = {.dead_man = true, .device_ok = true, .master_session_over = true};
  EXPECT_EQ(master.update(in), LoopState::kFault);
  EXPECT_EQ(master.fault(), FaultReason::kMasterSession);
}

}  // namespace
}  // namespace tsmh::haptics
