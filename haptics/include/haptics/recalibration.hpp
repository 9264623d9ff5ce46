#pragma once
// One-button recalibration and the drift alarm, the loop's side
// and the worker's side of one exchange.
//
// Re-routing the endoscope changes the sheaths' wrap and so the capstan
// friction: mostly a common scale of the model's sliding levels, while the
// stiffness of a reversal's transition (the tendon's own elasticity, theta)
// stays. Each direction's level lives in its own sheath of the pair, and a
// bend wraps the two by different amounts, so recalibration re-identifies
// the levels' scale per direction of sliding (`per_direction`, the default;
// else one common scale) and applies them to the model's levels
// (RecalibrationScale::kLevels, FrictionDynamics::set_level_scales: the state
// and so the friction of the instant stay, no jump), or, for models without
// a level, one common scale to the model's output (kOutput: F = gamma z
// scaled, which scales theta with the levels):
//
//  * the loop (tick, estimate): applies the scale, ramping it towards a new
//    target at `ramp_per_s` (no jump in rendered torque), runs the drift
//    monitor per joint, and after a request (master button or an LCM
//    request, `request()`, any thread) copies `collect_s` of samples per
//    joint into buffers allocated at construction;
//  * the worker (`identify_pending()`, a non-real-time thread) fits the
//    scale on those samples (kLevels: replaying them through its own copy of
//    each joint's model; kOutput: least squares), validates it against them
//    and publishes the result; the loop picks it up on a later tick.
//
// The hand-over is one atomic phase with acquire/release ordering: the loop
// writes the buffers only while collecting, the worker reads them only while
// identifying. Nothing on the loop's side allocates, locks, blocks or waits
// for the worker.

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string_view>
#include <vector>

#include "estimator/distal_estimator.hpp"
#include "estimator/friction_model.hpp"
#include "haptics/drift_monitor.hpp"
#include "haptics/joint_array.hpp"

namespace tsmh::haptics {

/// HAPTIC_STATUS calibration_state.
enum class CalibrationState : std::int32_t {
  kIdle = 0,         ///< never asked
  kCollecting = 1,   ///< recording free motion after a request
  kIdentifying = 2,  ///< the worker fits and validates
  kApplied = 3,      ///< last request: new scale applied (ramping in)
  kRefused = 4,      ///< last request refused: calibration_reason says why
};

/// HAPTIC_STATUS calibration_reason (why the last request was refused).
enum class CalibrationReason : std::int32_t {
  kNone = 0,
  kMotionTooSmall = 1,  ///< too little stroke or sliding in both directions
  kNotFree = 2,         ///< the data shows contact
  kNotBetter = 3,       ///< the new scale does not fit the data better
  kImplausible = 4,     ///< the scale found is outside [min_scale, max_scale]
  kNoData = 5,          ///< no valid slave samples arrived while collecting
};
std::string_view to_string(CalibrationState s) noexcept;
std::string_view to_string(CalibrationReason r) noexcept;

/// What the recalibrated scale multiplies.
enum class RecalibrationScale {
  /// The model's sliding levels, theta and the state kept (the physics of a
  /// re-routed sheath); models without a level fall back to kOutput.
  kLevels,
  /// The model's friction output (levels and theta together).
  kOutput,
};

struct RecalibrationConfig {
  RecalibrationScale scale = RecalibrationScale::kLevels;
  double collect_s = 5.0;         ///< free motion recorded after a request
  double min_span_rad = 0.3;      ///< each requested joint's input angle must span this
  double min_sliding_s = 0.5;     ///< and slide (|xd| > 0.1 rad/s) this long each way
  double min_improvement = 0.10;  ///< RMS residual must fall by this fraction
  double min_scale = 0.25;        ///< plausible friction scales
  double max_scale = 4.0;
  double ramp_per_s = 0.5;  ///< applied scale moves towards the new one at this rate
  /// kLevels: a scale for each direction of sliding (xd >= 0, xd < 0), fitted
  /// from the common one; false: one scale for both.
  bool per_direction = true;
  /// Samples kept per joint (slave samples; allocated once).
  std::size_t capacity = 12000;
};

/// What one request produced, per joint (written by the worker).
struct CalibrationFigures {
  double scale = 1.0;           ///< the scale found: the mean of the two directions'
  double scale_positive = 1.0;  ///< the levels' scale sliding xd >= 0 (kLevels)
  double scale_negative = 1.0;  ///< sliding xd < 0; both = scale when common
  double scale_common = 1.0;    ///< the best single scale (as without per_direction)
  double rms_common = 0.0;      ///< the residual at scale_common, N m
  double rms_old = 0.0;         ///< residual tau_in - s R F with the scale in use, N m
  double rms_new = 0.0;         ///< with the scale found
  double span_rad = 0.0;        ///< stroke of the input angle
  double sliding_s = 0.0;       ///< time sliding in the less covered direction
  int contact_bins = 0;         ///< angle bins the contact check could judge (>= 2 needed)
  std::size_t samples = 0;
};

class Recalibration {
 public:
  /// `replicas`: per joint, a copy of the joint's friction model for the
  /// worker to replay the collected samples through (kLevels); a missing one,
  /// or a model without a level scale, makes that joint use kOutput.
  Recalibration(int joints, const RecalibrationConfig& config, const DriftConfig& drift,
                std::vector<std::unique_ptr<estimator::FrictionModel>> replicas = {});

  // ---- any thread ----
  /// Asks for a recalibration of the joints in `mask` (bit j: joint j).
  /// Taken by the loop on its next tick; ignored while one is running.
  void request(std::uint32_t mask) noexcept;

  // ---- the loop thread ----
  /// Scales a fresh valid estimate (friction and tau_out_est), feeds the
  /// drift monitor and, while collecting, the buffer. t: slave time, s.
  void on_estimate(int joint, double t, double x_in, estimator::Estimate& e,
                   double radius_m) noexcept;
  /// Once per tick: takes a request, ends collection after collect_s, picks
  /// up the worker's result and ramps the applied scales. `button`: the
  /// master's calibrate button (a press starts a request for every joint).
  void on_tick(double now_s, double dt, bool button) noexcept;
  /// The applied scale: the mean of the two directions' (they are equal
  /// unless per_direction found them apart).
  double applied_scale(int joint) const noexcept {
    return 0.5 * (applied_[idx(joint)][0] + applied_[idx(joint)][1]);
  }
  /// The applied scale of the levels sliding positive (xd >= 0) / negative.
  double applied_scale(int joint, bool negative) const noexcept {
    return applied_[idx(joint)][negative ? 1 : 0];
  }
  /// True when joint's scale goes to its model's levels: the loop then sets
  /// the applied scales on the joint's estimator before each update, and
  /// on_estimate() leaves the estimate as the model made it.
  bool scales_levels(int joint) const noexcept { return level_mode_[idx(joint)]; }
  const DriftMonitor& drift(int joint) const noexcept { return drift_[idx(joint)]; }

  // ---- the worker thread ----
  /// When a collection is complete: fits, validates, publishes. Returns true
  /// when it processed one. Allocates (off the loop).
  bool identify_pending();

  // ---- any thread (status, log) ----
  CalibrationState state() const noexcept {
    return static_cast<CalibrationState>(phase_.load(std::memory_order_acquire));
  }
  CalibrationReason reason() const noexcept {
    return static_cast<CalibrationReason>(reason_.load(std::memory_order_relaxed));
  }
  /// The joint the reason is about (-1: none).
  int reason_joint() const noexcept { return reason_joint_.load(std::memory_order_relaxed); }
  /// +1 per finished request (applied or refused).
  std::uint64_t results() const noexcept { return results_.load(std::memory_order_acquire); }
  /// Figures of the last finished request (read after results() changed).
  CalibrationFigures figures(int joint) const noexcept;
  std::uint32_t last_mask() const noexcept { return mask_.load(std::memory_order_relaxed); }
  /// Bit j: joint j's drift alarm is up (written by the loop).
  std::uint32_t drift_alarms() const noexcept {
    return drift_mask_.load(std::memory_order_relaxed);
  }
  double drift_scale(int joint) const noexcept {
    return drift_scale_[idx(joint)].load(std::memory_order_relaxed);
  }
  double target_scale(int joint, bool negative = false) const noexcept {
    return target_[idx(joint)][negative ? 1 : 0].load(std::memory_order_relaxed);
  }
  int joints() const noexcept { return joints_; }
  const RecalibrationConfig& config() const noexcept { return config_; }

 private:
  struct Sample {
    double t, x, xd, xdd, acc_sign, tau_in;
    double tension;  // N, mean proximal tension (NaN: not measured)
    double f_raw;    // R F of the model before output scaling, N m
  };
  static std::size_t idx(int j) noexcept { return static_cast<std::size_t>(j); }
  void identify_joint(int j, CalibrationReason& why, CalibrationFigures& fig);
  // kLevels: the scales that best replay the collected samples (and the
  // residuals at them and at the scales in use).
  void fit_level_scale(int j, CalibrationFigures& fig);
  // The replay's sum of squared residuals with the levels scaled by (k+, k-).
  double replay_sse(int j, double k_positive, double k_negative, std::size_t& scored);

  int joints_;
  RecalibrationConfig config_;
  std::array<DriftMonitor, kMaxJoints> drift_;
  // Per joint, [0]: sliding positive, [1]: negative (equal for kOutput).
  std::array<std::array<double, 2>, kMaxJoints> applied_{};
  std::array<std::array<std::atomic<double>, 2>, kMaxJoints> target_{};
  std::array<std::atomic<double>, kMaxJoints> drift_scale_{};
  std::array<std::vector<Sample>, kMaxJoints> buffer_;  // capacity reserved once
  std::array<bool, kMaxJoints> level_mode_{};
  std::array<double, kMaxJoints> radius_{};  // loop: the joint's pulley radius, m
  // The worker's copies of the joints' models (kLevels), used only by it.
  std::vector<std::unique_ptr<estimator::FrictionModel>> replicas_;
  std::array<std::size_t, kMaxJoints> count_{};
  std::array<std::array<double, 2>, kMaxJoints> scale_at_collect_{};  // in use, for rms_old
  std::array<CalibrationFigures, kMaxJoints> figures_{};  // worker writes, read after results_

  std::atomic<std::uint32_t> requested_{0};
  std::atomic<std::uint32_t> mask_{0};
  std::atomic<std::int32_t> phase_{static_cast<std::int32_t>(CalibrationState::kIdle)};
  std::atomic<std::int32_t> reason_{0};
  std::atomic<int> reason_joint_{-1};
  std::atomic<std::uint64_t> results_{0};
  std::atomic<std::uint32_t> drift_mask_{0};
  std::uint64_t results_seen_ = 0;  // loop: the last result it took
  double collect_start_s_ = -1.0;   // loop: slave-independent loop time
  bool button_was_ = false;
};

}  // namespace tsmh::haptics
