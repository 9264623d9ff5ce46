#pragma once
// The SLAVE_STATE the server tests' stand-in slaves publish: two joints,
// following, constant tendon tensions (so a known proximal torque
// R (T1 - T3)), pulley radius 0.01 m; the caller stamps seq and utime.

#include "bridge/samples.hpp"

namespace tsmh::haptics::test {

inline bridge::SlaveStateSample constant_tension_state(double t1_n, double t3_n) {
  bridge::SlaveStateSample s;
  s.num_joints = 2;
  s.status = 1;
  for (std::size_t j = 0; j < 2; ++j) {
    s.T1[j] = t1_n;
    s.T3[j] = t3_n;
    s.radius_m[j] = 0.01;
  }
  return s;
}

}  // namespace tsmh::haptics::test
