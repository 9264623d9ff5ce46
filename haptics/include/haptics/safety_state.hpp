#pragma once
// The server's state machine (after dVRK's explicit FAULT state):
//
//   DISABLED --dead-man pressed, device ok, no fault--> ENABLED
//   ENABLED  --dead-man released-----------------------> DISABLED
//   any      --e-stop, device fault/disconnect, slave or estimate lost, another
//              session on the slave or master link, internal error-----> FAULT
//   FAULT    --cause gone AND dead-man released--------> DISABLED
//
// FAULT latches: the operator must let go of the dead-man before torque can
// come back, so a cleared fault never re-enables under a held hand by itself.

#include <cstdint>
#include <string_view>

namespace tsmh::haptics {

enum class LoopState : std::int32_t { kDisabled = 0, kEnabled = 1, kFault = 2 };

enum class FaultReason : std::int32_t {
  kNone = 0,
  kEStop,
  kDevice,        ///< the master device reports fault or disconnected
  kSlaveLost,     ///< no slave state for longer than the slave timeout
  kEstimateLost,  ///< slave state arrives but no valid estimate for longer than its timeout
  /// A second keyed sender on SLAVE_STATE (another slave, a restarted one, a
  /// replay of an older session): the slave session is over (the server ends).
  kSlaveSession,
  /// The same on MASTER_STATE (the `lcm` master driver).
  kMasterSession,
};

std::string_view to_string(LoopState s) noexcept;
std::string_view to_string(FaultReason r) noexcept;

struct SafetyInputs {
  bool dead_man = false;
  bool e_stop = false;
  bool device_ok = false;
  bool slave_lost = false;
  bool estimate_lost = false;
  bool slave_session_over = false;   ///< another session on the slave link
  bool master_session_over = false;  ///< another session on the master link
};

class SafetyStateMachine {
 public:
  /// One tick; returns the new state.
  LoopState update(const SafetyInputs& in) noexcept;
  LoopState state() const noexcept { return state_; }
  FaultReason fault() const noexcept { return fault_; }

 private:
  void go(LoopState s) noexcept;

  LoopState state_ = LoopState::kDisabled;
  FaultReason fault_ = FaultReason::kNone;
};

}  // namespace tsmh::haptics
