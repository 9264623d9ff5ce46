#pragma once
// Per-tick record of what the loop saw and did, for the demo report, plots
// and A/B evaluation. Storage is allocated once before the loop starts;
// append() never allocates (rows past the capacity are counted and dropped).

#include <cstdint>
#include <string>
#include <vector>

#include "haptics/joint_array.hpp"

namespace tsmh::haptics {

struct TraceJoint {
  double master_q = 0;       ///< rad
  double slave_ref = 0;      ///< position reference sent, rad
  double tau_in = 0;         ///< proximal torque (naive feedback), N m
  double tau_out_est = 0;    ///< estimated distal torque, N m
  double torque_cmd = 0;     ///< torque written to the master after safety, N m
  double x_in = 0;           ///< slave motor angle, rad
  double x_out = 0;          ///< slave joint angle (encoder), rad
  double true_tau_out = 0;   ///< SLAVE_TRUTH: true distal torque, N m (NaN when unmatched)
  double true_x_out = 0;     ///< SLAVE_TRUTH: true joint angle, rad
  double indentation = 0;    ///< SLAVE_TRUTH: tissue indentation, m
  double contact_force = 0;  ///< SLAVE_TRUTH: tissue contact force, N
};

struct TraceRow {
  double t = 0;                 ///< s since the loop started
  std::int64_t state_seq = -1;  ///< SLAVE_STATE seq used (-1 none)
  std::int32_t state = 0;       ///< LoopState
  std::int32_t flags = 0;
  double lateness_us = 0;
  std::array<TraceJoint, kMaxJoints> joints{};
};

class Trace {
 public:
  Trace(int joints, std::size_t capacity);
  void append(const TraceRow& row) noexcept;
  std::size_t size() const noexcept { return size_; }
  std::uint64_t dropped() const noexcept { return dropped_; }
  int joints() const noexcept { return joints_; }
  const TraceRow& operator[](std::size_t i) const noexcept { return rows_[i]; }

  /// Writes the trace as CSV (atomic). Columns: t,state_seq,state,flags,
  /// lateness_us, then per joint j: q_j,ref_j,tau_in_j,tau_est_j,cmd_j,x_in_j,
  /// x_out_j,true_tau_out_j,true_x_out_j,indentation_j,contact_force_j.
  void write_csv(const std::string& path) const;

 private:
  int joints_;
  std::vector<TraceRow> rows_;
  std::size_t size_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace tsmh::haptics
