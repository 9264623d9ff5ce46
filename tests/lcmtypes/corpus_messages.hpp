#pragma once
// Encoded messages of every type of ours, for the decoder tests and the
// fuzzers' seed corpus (make_decoder_corpus): deterministic contents, any
// joint count.

#include <cmath>
#include <cstdint>
#include <string>
#include <tsmh/calibration_request_t.hpp>
#include <tsmh/haptic_status_t.hpp>
#include <tsmh/master_command_t.hpp>
#include <tsmh/master_force_t.hpp>
#include <tsmh/master_state_t.hpp>
#include <tsmh/slave_state_t.hpp>
#include <tsmh/slave_truth_t.hpp>
#include <vector>

namespace tsmh::lcmtypes::test {

using Bytes = std::vector<std::uint8_t>;

inline std::vector<double> ramp(int n, double base) {
  std::vector<double> v(static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j)
    v[static_cast<std::size_t>(j)] = base + 0.125 * j;
  return v;
}

inline void fill(tsmh::slave_state_t& m, int n) {
  m.x_in = ramp(n, 0.1);
  m.x_out = ramp(n, 0.2);
  if (n > 0) m.x_out[0] = std::nan("");  // a joint without its encoder
  m.T1 = ramp(n, 30.0);
  m.T3 = ramp(n, 20.0);
  m.radius_m = ramp(n, 0.01);
  m.status = 1;
}
inline void fill(tsmh::slave_truth_t& m, int n) {
  m.tau_out = ramp(n, 0.05);
  m.friction = ramp(n, 1.5);
  m.tau_in = ramp(n, 0.1);
  m.x_out = ramp(n, 0.2);
  m.contact_force = ramp(n, 0.0);
  m.indentation = ramp(n, 0.001);
}
inline void fill(tsmh::master_command_t& m, int n) {
  m.position_ref = ramp(n, -0.3);
  m.enable = 1;
  m.clutch = 0;
}
inline void fill(tsmh::master_state_t& m, int n) {
  m.q = ramp(n, 0.01);
  m.qd = ramp(n, -0.5);
  m.buttons = 1;
  m.status = 0;
}
inline void fill(tsmh::master_force_t& m, int n) {
  m.torque = ramp(n, -0.094);
  m.enable = 1;
}
inline void fill(tsmh::haptic_status_t& m, int n) {
  m.state = 1;
  m.feedback_source = 0;
  m.rate_hz = 1000.0;
  m.lateness_p50_us = 3.0;
  m.lateness_p99_us = 20.0;
  m.lateness_max_us = 80.0;
  m.compute_p99_us = 9.0;
  m.overruns = 0;
  m.slave_age_ms = 1.0;
  m.slave_rejected = 2;
  m.slave_seq_gaps = 0;
  m.slave_latency_p99_us = std::nan("");
  m.flags = 0b101;
  m.tau_in = ramp(n, 0.1);
  m.tau_out_est = ramp(n, 0.05);
  m.friction_est = ramp(n, 1.5);
  m.torque_cmd = ramp(n, -0.09);
  m.master_q = ramp(n, 0.01);
  m.oscillation_trips = 0;
  m.oscillation_rms = ramp(n, 0.0);
  m.passivity_energy = ramp(n, 0.0);
  m.passivity_dissipated = ramp(n, 0.0);
  m.calibration_state = 0;
  m.calibration_reason = 0;
  m.calibration_joint = -1;
  m.friction_scale = ramp(n, 1.0);
  m.drift_scale = ramp(n, 1.0);
}
inline void fill(tsmh::calibration_request_t& m, int n) {
  m.recalibrate.assign(static_cast<std::size_t>(n), 1);
}

/// A message of `n` joints, encoded (with LCM's type hash).
template <class Message>
Bytes encoded(int n, std::int64_t seq = 42) {
  Message m{};
  m.utime = 1'700'000'000'000'000;
  m.seq = seq;
  m.num_joints = n;
  fill(m, n);
  Bytes b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

/// Overwrites the big-endian num_joints (bytes 24..27) of an encoded message.
inline void set_num_joints(Bytes& b, std::int32_t n) {
  const auto u = static_cast<std::uint32_t>(n);
  for (int i = 0; i < 4; ++i)
    b[24 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(u >> (24 - 8 * i));
}

}  // namespace tsmh::lcmtypes::test
