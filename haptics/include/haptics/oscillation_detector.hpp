#pragma once
// Safety rule for an oscillation that stays inside the torque limits (issue
// 21): a force loop closed through a long delay can ring on hard tissue
// although each side is stable alone, and neither the clamp nor the rate
// limit catches it. Per joint, the rendered torque is band-passed (the band
// of such oscillations: a few hertz to a few tens; the slow presses of an
// operator lie below it), squared and averaged over a window: the band
// energy. Above threshold^2 on any joint, for at least min_crossings swings
// of the band signal from beyond -threshold/2 to beyond +threshold/2 or back (an oscillation, not
// the single swing a step leaves in a band-pass), the detector trips: its gain falls to 0 over
// fade_s and stays there at least hold_s and until every joint's band energy is back under
// (threshold/2)^2, then rises over recover_s. The loop multiplies the torque request by the gain
// before the safety filter, so clamp and rate limit still hold.
//
// Pure value type: no clock, no threads, no allocation; cost per tick is
// two biquads and one average per joint.

#include <array>
#include <cstdint>

#include "haptics/joint_array.hpp"

namespace tsmh::haptics {

struct OscillationConfig {
  bool enabled = true;
  double band_low_hz = 2.0;    ///< high-pass corner (presses are slower)
  double band_high_hz = 40.0;  ///< low-pass corner (estimator noise is faster)
  double threshold_nm = 0.03;  ///< band RMS over the window that trips
  double window_s = 0.5;       ///< averaging time constant of the band energy
  int min_crossings = 4;       ///< band sign changes above threshold before tripping (2 cycles)
  double fade_s = 0.05;        ///< full force to zero once tripped
  double hold_s = 1.0;         ///< zero force at least this long
  double recover_s = 0.5;      ///< zero back to full force
};

/// Throws std::invalid_argument naming the field (safety.oscillation.*).
void validate(const OscillationConfig& c, double rate_hz);

/// Second-order section, direct form II transposed.
struct Biquad {
  double b0 = 1, b1 = 0, b2 = 0, a1 = 0, a2 = 0;
  double z1 = 0, z2 = 0;
  double step(double x) noexcept {
    const double y = b0 * x + z1;
    z1 = b1 * x - a1 * y + z2;
    z2 = b2 * x - a2 * y;
    return y;
  }
  /// Butterworth (Q = 1/sqrt 2) by the bilinear transform, prewarped.
  static Biquad lowpass(double fc_hz, double fs_hz) noexcept;
  static Biquad highpass(double fc_hz, double fs_hz) noexcept;
};

class OscillationDetector {
 public:
  /// `rate_hz`: the loop rate the filters are designed for.
  OscillationDetector(int joints, const OscillationConfig& c, double rate_hz);

  /// One tick with the torque rendered at the previous tick; returns the gain
  /// (0..1) for this tick's request. Non-finite torque counts as 0.
  double update(const JointArray& rendered, double dt_s) noexcept;

  /// Filters and energy back to rest (the loop calls it while torque is
  /// disabled, so the step to zero torque is never read as an oscillation).
  /// A trip in progress continues.
  void reset_signal() noexcept;

  bool tripped() const noexcept { return tripped_; }
  double gain() const noexcept { return gain_; }
  /// Band RMS per joint, N m (for HAPTIC_STATUS and the benchmark).
  double band_rms(int joint) const noexcept;
  std::uint64_t trips() const noexcept { return trips_; }
  const OscillationConfig& config() const noexcept { return c_; }

 private:
  int joints_;
  OscillationConfig c_;
  std::array<Biquad, kMaxJoints> hp_{}, lp_{};
  std::array<double, kMaxJoints> energy_{};
  std::array<double, kMaxJoints> last_band_{};  // side of the last swing: +1, -1, 0 none yet
  std::array<int, kMaxJoints> crossings_{};     // sign changes while above threshold
  bool tripped_ = false;
  double tripped_for_s_ = 0.0;
  double gain_ = 1.0;
  std::uint64_t trips_ = 0;
};

}  // namespace tsmh::haptics
