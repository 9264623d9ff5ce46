#include "haptics/safety_state.hpp"

#include "realtime/enum_names.hpp"

namespace tsmh::haptics {

std::string_view to_string(LoopState s) noexcept {
  return realtime::enum_name<LoopState::kFault>(s, {"DISABLED", "ENABLED", "FAULT"});
}

std::string_view to_string(FaultReason r) noexcept {
  return realtime::enum_name<FaultReason::kMasterSession>(
      r,
      {"none", "e-stop pressed", "master device fault or disconnected", "slave state lost",
       "torque estimate lost",
       "another slave session on the link (a second keyed slave, a restarted one or a replay)",
       "another master session on the link (a second keyed master, a restarted one or a replay)"});
}

void SafetyStateMachine::go(LoopState s) noexcept {
  state_ = s;
}

LoopState SafetyStateMachine::update(const SafetyInputs& in) noexcept {
  FaultReason cause = FaultReason::kNone;
  if (in.e_stop)
    cause = FaultReason::kEStop;
  else if (in.slave_session_over)
    cause = FaultReason::kSlaveSession;
  else if (in.master_session_over)
    cause = FaultReason::kMasterSession;
  else if (!in.device_ok)
    cause = FaultReason::kDevice;
  else if (in.slave_lost)
    cause = FaultReason::kSlaveLost;
  else if (in.estimate_lost)
    cause = FaultReason::kEstimateLost;

  if (cause != FaultReason::kNone) {
    // The first cause is kept, except that the end of the session (another
    // session on a link) overrides any: it is final and what the operator
    // must be told.
    const bool session_over =
        cause == FaultReason::kSlaveSession || cause == FaultReason::kMasterSession;
    if (state_ != LoopState::kFault || session_over) fault_ = cause;
    go(LoopState::kFault);
    return state_;
  }
  switch (state_) {
    case LoopState::kFault:
      if (!in.dead_man) {
        fault_ = FaultReason::kNone;
        go(LoopState::kDisabled);
      }
      break;
    case LoopState::kDisabled:
      if (in.dead_man) go(LoopState::kEnabled);
      break;
    case LoopState::kEnabled:
      if (!in.dead_man) go(LoopState::kDisabled);
      break;
  }
  return state_;
}

}  // namespace tsmh::haptics
