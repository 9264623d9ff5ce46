#pragma once
// Deterministic samples for the bridge tests and the test peer process: the
// values encode seq, so a receiver can check it got the right message.

#include <cstdint>

#include "bridge/samples.hpp"

namespace tsmh::bridge::test {

/// A plausible 2-joint SLAVE_STATE whose values encode `seq`.
inline SlaveStateSample make_state(std::int64_t seq, std::int64_t utime, int joints = 2) {
  SlaveStateSample s;
  s.utime = utime;
  s.seq = seq;
  s.num_joints = joints;
  s.status = 1;
  for (int j = 0; j < joints; ++j) {
    const auto k = static_cast<std::size_t>(j);
    s.x_in[k] = 0.001 * static_cast<double>(seq) + j;
    s.x_out[k] = 0.0009 * static_cast<double>(seq) + j;
    s.T1[k] = 10.0 + 0.01 * static_cast<double>(seq);
    s.T3[k] = 5.0 + j;
    s.radius_m[k] = 0.01;
  }
  return s;
}

inline SlaveTruthSample make_truth(std::int64_t seq, std::int64_t utime, int joints = 2) {
  SlaveTruthSample t;
  t.utime = utime;
  t.seq = seq;
  t.num_joints = joints;
  for (int j = 0; j < joints; ++j) {
    const auto k = static_cast<std::size_t>(j);
    t.tau_out[k] = 0.04 - 0.0001 * static_cast<double>(seq) + j;
    t.friction[k] = 1.0;
    t.tau_in[k] = 0.05;
  }
  return t;
}

}  // namespace tsmh::bridge::test
