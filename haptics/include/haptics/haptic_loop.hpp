#pragma once
// One tick of the haptic loop:
//   read the master -> newest SLAVE_STATE -> estimator per joint -> force
//   mapping -> safety -> write the master -> MASTER_COMMAND (position mapping,
//   clutch, enable) -> HAPTIC_STATUS every status_every ticks -> trace.
// tick() takes the time from its caller, so the same code runs under the
// real-time runner (CLOCK_MONOTONIC) and in deterministic simulated time.
// Nothing in tick() allocates, locks, blocks or prints.

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "bridge/samples.hpp"
#include "estimator/distal_estimator.hpp"
#include "haptics/force_mapping.hpp"
#include "haptics/joint_array.hpp"
#include "haptics/oscillation_detector.hpp"
#include "haptics/passivity.hpp"
#include "haptics/position_mapping.hpp"
#include "haptics/recalibration.hpp"
#include "haptics/safety_filter.hpp"
#include "haptics/safety_state.hpp"
#include "haptics/slave_link.hpp"
#include "haptics/trace.hpp"
#include "master_devices/device.hpp"
#include "realtime/histogram.hpp"

namespace tsmh::haptics {

/// What is rendered: the model's estimate, the proximal torque (what you feel
/// without the model), or nothing — for A/B feel tests.
enum class FeedbackSource : std::int32_t { kEstimated = 0, kNaive = 1, kNone = 2 };
std::string_view to_string(FeedbackSource s) noexcept;

struct LoopConfig {
  /// The loop rates haptic-server accepts, Hz: from its configuration, from
  /// --rate, and in the loop's own check (one range, checked against these).
  static constexpr double kMinRateHz = 1.0;
  static constexpr double kMaxRateHz = 4000.0;

  int joints = 2;
  double rate_hz = 1000.0;
  FeedbackSource source = FeedbackSource::kEstimated;
  std::array<ForceMapping, kMaxJoints> force{};
  std::array<PositionMappingConfig, kMaxJoints> position{};
  std::array<JointSafetyLimits, kMaxJoints> limits{};
  SafetyTiming timing{};
  double slave_timeout_s = 1.0;  ///< no slave state this long: FAULT
  /// A device reading that is merely late (DeviceReading::stale: the console
  /// missed a few periods) zeroes torque at once but only faults when it lasts
  /// this long; an unplug or a device fault faults at once.
  double device_stale_fault_s = 0.050;
  /// Slave state arrives but some joint has had no valid estimate this long:
  /// FAULT. Before that the last valid estimate is held and faded like a
  /// stale slave (SafetyTiming), so losing the estimate is never a step.
  double estimate_fault_s = 0.5;
  int status_every = 10;  ///< HAPTIC_STATUS every this many ticks (100 Hz at 1 kHz)
  /// Sets rate_hz and keeps HAPTIC_STATUS at about 100 Hz (status_every).
  void set_rate(double hz) noexcept {
    rate_hz = hz;
    status_every = std::max(1, static_cast<int>(std::lround(hz / 100.0)));
  }
  OscillationConfig oscillation{};  ///< safety.oscillation
  PassivityConfig passivity{};      ///< passivity, off by default

  // Drift alarm and recalibration (haptic-server.md).
  DriftConfig drift{};                  ///< drift alarm (recalibration.hpp)
  RecalibrationConfig recalibration{};  ///< one-button recalibration
};

struct LoopCounters {
  std::uint64_t ticks = 0;
  std::uint64_t overruns = 0;       ///< deadlines skipped (set by the runner)
  std::uint64_t slave_samples = 0;  ///< new SLAVE_STATE samples used
  std::uint64_t estimator_rejects = 0;
  std::uint64_t nonfinite_requests = 0;
  std::uint64_t saturated_ticks = 0;
  std::uint64_t rate_limited_ticks = 0;
  std::uint64_t stale_ticks = 0;
  std::uint64_t device_stale_ticks = 0;  ///< master readings too old: torque zeroed, no fault
  std::uint64_t estimator_resets = 0;    ///< slave clock discontinuities: estimators re-initialised
  std::uint64_t estimate_lost_ticks = 0;  ///< ticks with some joint's estimate invalid
  std::uint64_t faults = 0;               ///< entries into FAULT
  std::uint64_t oscillation_trips = 0;    ///< sustained oscillations detected (force faded)
  std::uint64_t oscillation_ticks = 0;    ///< ticks with the oscillation fade below full force
  std::uint64_t passivity_ticks = 0;  ///< ticks with the passivity controller damping some joint
};

/// HAPTIC_STATUS flags (lcmtypes/haptic_status_t.lcm).
namespace status_flags {
inline constexpr std::int32_t kStaleFade = 1 << 0;
inline constexpr std::int32_t kEStop = 1 << 1;
inline constexpr std::int32_t kDeadManReleased = 1 << 2;
inline constexpr std::int32_t kSaturated = 1 << 3;
inline constexpr std::int32_t kRateLimited = 1 << 4;
inline constexpr std::int32_t kEstimateLost = 1 << 5;  ///< some joint has no valid estimate
inline constexpr std::int32_t kClockReset = 1 << 6;    ///< slave clock jumped in this period
inline constexpr std::int32_t kOverrun = 1 << 7;       ///< a deadline was missed in this period
// Bits 8-11 are left to other features; these two are delayed teleoperation's.
inline constexpr std::int32_t kOscillation = 1 << 12;  ///< oscillation detected: force faded
inline constexpr std::int32_t kPassivityActive =
    1 << 13;  ///< passivity controller damped in this period

// Drift alarm and recalibration.
inline constexpr std::int32_t kDriftSuspected = 1 << 8;  ///< some joint's friction drifted
inline constexpr std::int32_t kRecalibrating = 1 << 9;   ///< collecting or identifying
/// Another keyed sender on the slave or master link ended the session
/// (bridge/link_session.hpp): FAULT, the server stops.
inline constexpr std::int32_t kOtherSession = 1 << 14;
}  // namespace status_flags

/// What the loop thread reports to a non-real-time thread (which logs it):
/// plain atomics written with relaxed stores, never a lock or a print in the
/// loop.
struct LoopEvents {
  std::atomic<std::uint64_t> estimator_resets{0};
  std::atomic<std::int64_t> last_reset_jump_us{0};     ///< utime step that caused the last reset
  std::atomic<std::uint32_t> estimate_lost_joints{0};  ///< bit j: joint j has no valid estimate
  std::atomic<std::int32_t> state{0};                  ///< LoopState
  std::atomic<std::int32_t> fault{0};                  ///< FaultReason
  std::atomic<std::uint64_t> overruns{0};
  std::atomic<std::int64_t> worst_lateness_ns{0};  ///< since the reader last exchanged it with 0
  std::atomic<std::uint64_t> slave_samples{0};     ///< new SLAVE_STATE samples used so far
  std::atomic<std::uint64_t> faults{0};            ///< entries into FAULT so far
  // The live status line (updated with every HAPTIC_STATUS, 100 Hz):
  std::atomic<std::uint64_t> ticks{0};
  std::atomic<double> rate_hz{0.0};                         ///< over the last status period
  std::atomic<double> lateness_p99_us{0.0};                 ///< this second's window
  std::atomic<double> lateness_max_us{0.0};                 ///< this second's window
  std::atomic<double> slave_age_ms{-1.0};                   ///< -1: no slave state yet
  std::array<std::atomic<double>, kMaxJoints> torque_nm{};  ///< written to the master
};

class HapticLoop {
 public:
  /// `estimators` has one entry per joint. `trace` may be null. Throws
  /// std::invalid_argument on an inconsistent configuration.
  HapticLoop(const LoopConfig& config, master_devices::Device& device, SlaveLink& link,
             std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> estimators,
             TraceSink* trace = nullptr);

  /// One tick at time now_ns (CLOCK_MONOTONIC, or simulated). `lateness_ns`:
  /// how late this tick started against the absolute schedule, i.e. the
  /// first deadline that was due and had not run yet (for statistics; after a
  /// stall it includes the skipped periods).
  void tick(std::int64_t now_ns, std::int64_t lateness_ns = 0) noexcept;

  /// Compute time of the tick that just ran, and deadlines skipped after it.
  void record_compute(std::int64_t compute_ns, std::int64_t skipped) noexcept;

  /// Zero torque, torque output disabled, slave commanded to hold. Every exit
  /// path calls this first. Idempotent; never throws.
  void shutdown() noexcept;

  LoopState state() const noexcept { return machine_.state(); }
  FaultReason fault() const noexcept { return machine_.fault(); }
  const LoopCounters& counters() const noexcept { return counters_; }
  const estimator::Estimate& estimate(int joint) const noexcept {
    return estimates_[static_cast<std::size_t>(joint)];
  }
  const realtime::LinearHistogram& lateness() const noexcept { return lateness_; }
  const realtime::LinearHistogram& compute() const noexcept { return compute_; }
  double rate_hz() const noexcept { return config_.rate_hz; }
  /// Mean tick rate measured over the whole run (ticks / elapsed time).
  double measured_rate_hz() const noexcept;
  int joints() const noexcept { return config_.joints; }
  bool passivity_enabled() const noexcept { return config_.passivity.enabled; }
  const OscillationDetector& oscillation() const noexcept { return oscillation_; }
  const PassivityChannel& passivity(int joint) const noexcept {
    return passivity_[static_cast<std::size_t>(joint)];
  }
  /// For a non-real-time thread: events to log (any thread may read).
  LoopEvents& events() noexcept { return events_; }
  /// Drift alarm and recalibration: request() and identify_pending() are for
  /// other threads (recalibration.hpp).
  Recalibration& calibration() noexcept { return calibration_; }
  const Recalibration& calibration() const noexcept { return calibration_; }

 private:
  // What one tick decided, step by step (tick()); status and trace publish
  // from it instead of re-deriving it.
  struct TickFacts {
    std::int64_t now_ns = 0;
    std::int64_t lateness_ns = 0;
    double dt = 0.0;                // s since the previous tick
    double slave_age_s = 0.0;       // since the newest SLAVE_STATE arrived; inf: none yet
    std::uint32_t lost_joints = 0;  // bit j: joint j has no valid estimate
    double lost_s = 0.0;            // how long some joint's estimate has been lost
    bool device_fresh = false;      // the master's reading is fresh (kOk)
    LoopState before = LoopState::kDisabled;
    LoopState state = LoopState::kDisabled;
    bool enabled = false;  // state == kEnabled
    /// This tick went into FAULT: monitors hear of it at once, not at the next
    /// status period (a server ending on the fault may not see one).
    bool fault_entered() const noexcept {
      return state == LoopState::kFault && before != LoopState::kFault;
    }
    JointArray request{};  // master torque asked for, before shaping and safety
    SafetyOutput out{};    // what safety let through (written to the device)
  };
  void begin_tick(std::int64_t now_ns, std::int64_t lateness_ns, TickFacts& f) noexcept;
  void take_slave_state(TickFacts& f) noexcept;
  void track_estimate_loss(TickFacts& f) noexcept;
  void request_feedback(TickFacts& f) noexcept;
  void decide_state(TickFacts& f) noexcept;
  void render(TickFacts& f) noexcept;
  void command_slave(const TickFacts& f) noexcept;
  void collect_truth() noexcept;
  void append_trace(const TickFacts& f) noexcept;
  std::int32_t status_flags_of(const TickFacts& f) const noexcept;
  void publish_status(const TickFacts& f) noexcept;
  void estimate() noexcept;                               // a new SLAVE_STATE in state_
  double slave_torque(std::size_t joint) const noexcept;  // what the source renders, slave N m
  // Delayed teleoperation (haptic_loop_passivity.cpp): the slave port's energy from each
  // new sample; the oscillation gain and the passivity correction of the
  // request; the master port's energy from what was rendered.
  void observe_slave_ports() noexcept;
  void shape_request(JointArray& request, double dt, bool enabled) noexcept;
  void observe_rendered(const SafetyOutput& out) noexcept;
  std::int32_t calibration_status(bridge::HapticStatusSample& st) const noexcept;
  void recalibrate(const TickFacts& f) noexcept;

  LoopConfig config_;
  TickFacts facts_;
  master_devices::Device& device_;
  SlaveLink& link_;
  std::vector<std::unique_ptr<estimator::DistalTorqueEstimator>> estimators_;
  TraceSink* trace_;

  Recalibration calibration_;
  SafetyStateMachine machine_;
  SafetyFilter safety_;
  OscillationDetector oscillation_;
  std::array<PassivityChannel, kMaxJoints> passivity_;
  bool passivity_in_period_ = false;
  bool passivity_enabled_ = false;  // the loop was enabled at the last tick
  std::array<PositionMapping, kMaxJoints> position_;
  std::array<estimator::Estimate, kMaxJoints> estimates_{};
  std::array<estimator::Estimate, kMaxJoints> held_{};  // the last valid estimate per joint
  std::int64_t estimate_lost_since_ns_ = -1;            // -1: every joint's estimate is valid
  std::int64_t last_utime_ = 0;  // of the last sample given to the estimators
  bool clock_reset_in_period_ = false;
  bool overrun_in_period_ = false;
  std::uint64_t status_ticks_ = 0;  // counters_.ticks at the last HAPTIC_STATUS
  std::int64_t status_ns_ = 0;      // its time
  LoopEvents events_;

  bridge::SlaveStateSample state_{};
  // The last few SLAVE_TRUTH samples by seq (slot seq % size), collected
  // around the state's read (take_slave_state): the newest truth is often a
  // pair ahead of the state by the time the trace row is written. seq -1
  // marks an empty slot.
  std::array<bridge::SlaveTruthSample, 4> truths_{};
  bridge::SlaveTruthSample truth_in_{};
  std::uint64_t truth_version_ = 0;
  std::uint64_t state_version_ = 0;
  std::uint64_t calibration_request_version_ = 0;
  bridge::CalibrationRequestSample calibration_request_{};
  bool have_state_ = false;
  master_devices::DeviceReading reading_{};
  bridge::MasterCommandSample command_{};
  bridge::HapticStatusSample status_{};
  master_devices::JointArray device_torque_{};

  std::int64_t device_stale_since_ns_ = -1;  // -1: the device's reading is fresh
  std::int64_t first_ns_ = 0;
  std::int64_t last_ns_ = 0;
  std::int64_t command_seq_ = 0;
  std::int64_t status_seq_ = 0;
  bool device_enabled_ = false;
  bool shut_down_ = false;
  LoopCounters counters_;
  realtime::LinearHistogram lateness_;
  realtime::LinearHistogram compute_;
  realtime::LogHistogram window_lateness_;  // coarse, cheap to summarise at 100 Hz; 1 s windows
  realtime::LogHistogram window_compute_;
};

}  // namespace tsmh::haptics
