#pragma once
// The drivers' clock: realtime::Clock (realtime/clock.hpp, the project's one
// clock module). Drivers and transports do not read the host clock
// themselves: they read the Clock given to their constructor
// (MonotonicClock by default), so a test can give them a ManualClock and let
// time pass by advancing it instead of sleeping.

#include <memory>

#include "realtime/clock.hpp"

namespace tsmh::master_devices {

using realtime::Clock;
using realtime::ManualClock;
using realtime::MonotonicClock;

/// The default for a driver's clock parameter.
inline std::shared_ptr<const Clock> monotonic_clock() {
  return std::make_shared<MonotonicClock>();
}

}  // namespace tsmh::master_devices
