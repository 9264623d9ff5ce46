#pragma once
// The fault rules every driver gets from DriverBase, checked the same way on
// each driver (console, lcm, sim, haply, the skeleton): a fault the host
// raises turns torque off at the device, whatever the loop keeps writing or
// enabling; a second cause does not replace the first; last_error() says it
// in the same words on every driver; a cleared fault comes back disabled.
// A driver that kept its own copy of these rules would drift from them (the
// haply and skeleton drivers once let a later fault overwrite the first and
// said nothing in last_error() about a fault the host raised).

#include <gtest/gtest.h>

#include <functional>

#include "master_devices/driver_base.hpp"

namespace tsmh::master_devices::testing {

struct DriverProbe {
  Device& device;
  std::function<std::int64_t()> now;         ///< the host time read() is given
  std::function<double()> torque_at_device;  ///< joint 0's torque as the device last got it
  std::function<void()> step;                ///< lets the driver's I/O side run once
};

/// Steps until `pred` holds (at most `steps` times).
inline bool within_steps(const DriverProbe& p, const std::function<bool()>& pred,
                         int steps = 3000) {
  for (int i = 0; i < steps; ++i) {
    if (pred()) return true;
    p.step();
  }
  return pred();
}

/// `p.device` is open and reading OK. `tau0` is a torque within its limits.
inline void expect_shared_fault_rules(const DriverProbe& p, double tau0) {
  Device& d = p.device;
  ASSERT_NE(dynamic_cast<DriverBase*>(&d), nullptr) << "the driver derives from DriverBase";
  JointArray tau{};
  tau[0] = tau0;
  auto loop_cycle = [&] {
    const DeviceReading r = d.read(p.now());
    d.write_torque(tau);
    return r;
  };
  d.set_enabled(true);
  ASSERT_TRUE(within_steps(p, [&] {
    loop_cycle();
    return p.torque_at_device() != 0.0;
  })) << "torque reaches the device while enabled";

  d.raise_fault(FaultCode::kHostRequested);
  d.raise_fault(FaultCode::kWorkspace);  // a second cause does not replace the first
  d.set_enabled(true);                   // nor does the loop asking again turn torque on
  EXPECT_EQ(d.status(), DeviceStatus::kFault);
  EXPECT_EQ(d.last_error(), "fault raised by the host");
  EXPECT_TRUE(within_steps(p, [&] {
    loop_cycle();
    return p.torque_at_device() == 0.0;
  })) << "the fault zeroes the torque at the device";
  const DeviceReading faulted = loop_cycle();
  EXPECT_EQ(faulted.status, DeviceStatus::kFault);
  EXPECT_EQ(faulted.fault, FaultCode::kHostRequested);
  EXPECT_FALSE(faulted.enabled);
  EXPECT_EQ(faulted.tau_commanded[0], 0.0);

  ASSERT_TRUE(d.clear_fault());
  EXPECT_EQ(d.last_error(), "");
  EXPECT_NE(d.status(), DeviceStatus::kFault);
  for (int i = 0; i < 20; ++i) {
    loop_cycle();
    p.step();
    EXPECT_EQ(p.torque_at_device(), 0.0) << "a cleared fault comes back disabled";
  }
  EXPECT_FALSE(loop_cycle().enabled);
}

}  // namespace tsmh::master_devices::testing
