#pragma once
// Online differentiation of a sampled, quantised angle into velocity and
// acceleration: a three-state Kalman filter (angle, velocity, acceleration)
// driven by white jerk, discretised for each actual sample interval, so
// uneven time stamps and dropped samples are handled exactly rather than
// assumed away. The sign of the acceleration, on which eq. (4) and the
// sliding-level branches switch, passes through a Schmitt trigger whose
// threshold follows the filter's own acceleration uncertainty, so it does not
// chatter on encoder quantisation. Delay and noise: docs/friction-model.md.

#include <array>
#include <numbers>

namespace tsmh::estimator {

struct DifferentiatorConfig {
  /// Spectral density of the jerk the filter expects, (rad/s^3)^2/Hz. Larger
  /// follows faster motion with less lag and more noise.
  double jerk_psd = 300.0;
  /// Encoder quantum, rad; its uniform error (quantum^2/12) is the measurement
  /// noise together with position_noise.
  double quantum = 2.0 * std::numbers::pi / 40960.0;
  /// Additional white measurement noise on the angle, rad (standard deviation).
  double position_noise = 0.0;
  /// |xdd| above which sgn(xdd) becomes +-1 (after acc_sign_dwell), rad/s^2;
  /// it returns to 0 when the estimate crosses zero. Negative: automatic,
  /// 0.75 x the steady-state acceleration uncertainty at 1 kHz.
  double acc_sign_threshold = -1.0;
  /// How long |xdd| must stay beyond the threshold before sgn(xdd) turns +-1, s.
  double acc_sign_dwell = 0.010;
  /// A gap longer than this (s) restarts the filter at the new sample.
  double max_gap = 1.0;
};

struct Derivatives {
  double x = 0.0;      ///< filtered angle, rad
  double xd = 0.0;     ///< rad/s
  double xdd = 0.0;    ///< rad/s^2
  int acc_sign = 0;    ///< debounced sgn(xdd)
  bool valid = false;  ///< false for a rejected sample (non-finite, time not increasing)
};

class Differentiator {
 public:
  explicit Differentiator(const DifferentiatorConfig& config = {});

  /// Feeds the sample (t in s, x in rad). Never allocates or throws.
  /// Non-finite input or t <= last t is rejected: state unchanged, valid = false.
  Derivatives update(double t, double x) noexcept;
  void reset() noexcept;

  double acc_sign_threshold() const { return threshold_; }
  const Derivatives& last() const { return out_; }

 private:
  void start(double t, double x) noexcept;

  DifferentiatorConfig cfg_;
  double r_;                   // measurement variance, rad^2
  double threshold_;           // Schmitt trigger half-width, rad/s^2
  int pending_sign_ = 0;       // sign waiting out the dwell time
  double pending_time_ = 0.0;  // how long it has been waiting, s
  bool started_ = false;
  double t_ = 0.0;
  std::array<double, 3> s_{};                 // angle, velocity, acceleration
  std::array<std::array<double, 3>, 3> p_{};  // state covariance
  Derivatives out_;
};

}  // namespace tsmh::estimator
