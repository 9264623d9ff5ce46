#pragma once
// Drift alarm: re-routing the endoscope changes the sheaths' wrap
// and with it the capstan friction, so the identified model drifts. During
// free motion the proximal torque is almost all friction, tau_in ~ R F, so
// the residual r = tau_in - R F_model grows in proportion to the model's
// friction when its scale is off: r ~ (k - 1) R F_model. The monitor fits
// r = a + c R F_model by exponentially forgotten least squares over sliding
// samples; c estimates the scale error (k - 1), the intercept a absorbs a
// one-sided load (contact on one side, a tare offset) so that it does not
// read as drift, and samples whose estimated distal torque is larger than the
// model's friction torque (clear contact) are left out, and so are samples
// still in the friction's transition after a reversal (|F| below 0.8 of the
// model's sliding level). The alarm rises when |c| stays above
// `threshold` for `hold_s` with both directions in the window, and clears below half of it
// (hysteresis). A pure value type: no allocation, no clock, no I/O.

#include "estimator/distal_estimator.hpp"

namespace tsmh::haptics {

struct DriftConfig {
  bool enabled = true;
  double time_constant_s = 2.0;  ///< forgetting of the least squares
  double min_speed_rad_s = 0.1;  ///< only sliding samples (|xd| above) count
  /// Samples whose estimated distal torque exceeds this many times the
  /// model's friction torque are contact, not free motion, and are left out
  /// (so are samples near reversals, where |F| is small and the model is
  /// least sure). A drift up to twice the friction still passes.
  double contact_gate_ratio = 1.0;
  /// Only samples whose friction has come within this fraction of the
  /// model's sliding level count (|F| >= min_saturation x gamma Ff; not
  /// applied when the model has no level). Within the friction's transition
  /// after a reversal the residual's slope against F reflects the
  /// transition's shape, not a scale: a joint that only sways (strokes
  /// shorter than the transition, backlash compensation jumping the motor
  /// across the dead zone) would otherwise be judged on such samples. The
  /// gate depends on the model's state only, so contact samples are not
  /// favoured over free ones.
  double min_saturation = 0.8;
  double threshold = 0.25;  ///< |scale - 1| beyond this is drift
  double hold_s = 1.0;      ///< for this long (and as long below threshold / 2 to clear)
  /// Each direction must carry this much weight in the window (samples x
  /// forgetting; 150 ~ 0.15 s of sliding at 1 kHz) before the scale is judged.
  double min_weight_per_direction = 150.0;
};

class DriftMonitor {
 public:
  explicit DriftMonitor(const DriftConfig& config = {}) noexcept : config_(config) {}

  /// One estimate (the loop's, with the friction scale already applied) at
  /// slave time t, s. Invalid estimates are ignored.
  void update(double t, const estimator::Estimate& e, double radius_m) noexcept;
  void reset() noexcept;

  /// Friction scale the data asks for relative to the model (1 + c); 1 until judged.
  double scale() const noexcept { return judged_ ? 1.0 + c_ : 1.0; }
  /// True when the window holds enough sliding in both directions to judge.
  bool judged() const noexcept { return judged_; }
  bool alarm() const noexcept { return alarm_; }

 private:
  DriftConfig config_;
  double t_last_ = 0.0;
  bool started_ = false;
  // Forgotten sums of w, f, f^2, r, r f; weight per direction.
  double s0_ = 0.0, sf_ = 0.0, sff_ = 0.0, sr_ = 0.0, srf_ = 0.0;
  double w_pos_ = 0.0, w_neg_ = 0.0;
  double c_ = 0.0;
  bool judged_ = false;
  bool alarm_ = false;
  double beyond_since_ = -1.0;  // t when |c| went beyond (resp. back within) the threshold
  double within_since_ = -1.0;
};

}  // namespace tsmh::haptics
