#pragma once
// Per-tick record of what the loop saw and did, for the demo report, plots
// and A/B evaluation. The loop appends through a TraceSink, which never
// allocates, locks or blocks:
//  - Trace: rows in memory, capacity fixed up front (tests, short runs);
//  - TraceSpool (the server): a fixed ring the loop pushes into and a
//    writer thread that streams the rows to an unlinked file on disk, so the
//    memory a trace takes does not grow with the run (docs/haptic-server.md,
//    "Trace and report memory"). At the end the file is mapped back as a Trace.
// Rows are stored compactly: only the configured joints, as doubles.

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "bridge/spsc_queue.hpp"
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

/// Doubles per stored row for `joints` joints.
constexpr std::size_t trace_row_width(int joints) noexcept {
  return 5 + 11 * static_cast<std::size_t>(joints);
}

/// Where the loop appends (loop thread only; never allocates, locks or blocks).
class TraceSink {
 public:
  virtual ~TraceSink() = default;
  virtual void append(const TraceRow& row) noexcept = 0;
  virtual int joints() const noexcept = 0;
};

class Trace final : public TraceSink {
 public:
  /// In memory, room for `capacity` rows (allocated here); rows past it are
  /// counted and dropped.
  Trace(int joints, std::size_t capacity);
  /// Read-only view of `rows` rows stored at `data` (kept alive by `owner`).
  Trace(int joints, const double* data, std::size_t rows, std::shared_ptr<const void> owner,
        std::uint64_t dropped);

  void append(const TraceRow& row) noexcept override;
  int joints() const noexcept override { return joints_; }
  std::size_t size() const noexcept { return size_; }
  std::uint64_t dropped() const noexcept { return dropped_; }
  /// Row i, decoded (by value).
  TraceRow operator[](std::size_t i) const noexcept;

  /// Writes the trace as CSV (atomic). Columns: t,state_seq,state,flags,
  /// lateness_us, then per joint j: q_j,ref_j,tau_in_j,tau_est_j,cmd_j,x_in_j,
  /// x_out_j,true_tau_out_j,true_x_out_j,indentation_j,contact_force_j.
  void write_csv(const std::string& path) const;

 private:
  int joints_;
  std::size_t width_;
  std::vector<double> storage_;  // in-memory mode
  const double* data_ = nullptr;
  std::size_t capacity_ = 0;
  std::size_t size_ = 0;
  std::uint64_t dropped_ = 0;
  std::shared_ptr<const void> owner_;  // mapped mode
};

/// Encodes a row into trace_row_width(joints) doubles.
void encode_trace_row(const TraceRow& row, int joints, double* out) noexcept;

class TraceSpool final : public TraceSink {
 public:
  /// Rows the loop may get ahead of the writer thread: 4 s at 1 kHz, 3 MB.
  static constexpr std::size_t kRingRows = 4096;

  /// Streams to an unlinked temporary file in `dir` (it disappears with the
  /// process, whatever happens); at most `max_rows` rows are kept. Throws
  /// std::runtime_error when the file cannot be created.
  TraceSpool(int joints, const std::filesystem::path& dir, std::uint64_t max_rows);
  ~TraceSpool() override;
  TraceSpool(const TraceSpool&) = delete;
  TraceSpool& operator=(const TraceSpool&) = delete;

  void append(const TraceRow& row) noexcept override;
  int joints() const noexcept override { return joints_; }

  /// Stops the writer after it has written every queued row and maps the
  /// file back. Throws std::runtime_error when writing failed (disk full).
  Trace finish();
  /// Rows the ring had no room for or past max_rows.
  std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
  /// Bytes on disk so far.
  std::uint64_t bytes_written() const noexcept {
    return written_.load(std::memory_order_relaxed) * trace_row_width(joints_) * sizeof(double);
  }

 private:
  void run() noexcept;

  int joints_;
  std::uint64_t max_rows_;
  int fd_ = -1;
  std::FILE* file_ = nullptr;
  std::uint64_t pushed_ = 0;  // loop thread
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::uint64_t> written_{0};
  std::atomic<bool> stop_{false};
  std::atomic<bool> failed_{false};
  std::atomic<int> failed_errno_{
      0};  ///< errno of the first failed write (EFBIG: a file-size limit)
  std::unique_ptr<bridge::SpscQueue<TraceRow, kRingRows>> ring_;
  std::thread writer_;
};

}  // namespace tsmh::haptics
