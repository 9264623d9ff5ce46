#pragma once
// Telling free motion from contact on a joint's proximal data alone (issue
// 17): a free joint's proximal torque stays inside the band of its sliding
// friction and that band does not move with the position; tissue adds a
// one-sided load that grows with position and stays while the joint holds
// still. Used by `tsm fit --free-motion` (identification/free_motion.hpp)
// and by haptic-server's recalibration, so it lives in the core library.

#include <string>
#include <vector>

namespace tsmh::estimator {

struct ContactCheckConfig {
  /// Contact when the midline of the hysteresis loop (mean of the up- and
  /// down-stroke proximal torque at the same angle) moves by more than this
  /// fraction of the loop's half-width across the stroke.
  double max_midline_shift = 0.25;
  /// Contact when the proximal torque leaves the sliding band by more than
  /// this fraction of its half-width for at least `max_excess_s`.
  double max_band_excess = 0.3;
  double max_excess_s = 0.1;
};

/// The figures behind the contact decision (reported, and quoted in errors).
struct ContactCheck {
  double band_half_width_nm = 0.0;  ///< half the sliding loop's height, N m
  double midline_shift_nm = 0.0;    ///< max - min of the loop's midline over the stroke
  double midline_shift_at_rad = 0.0;
  double longest_excess_s = 0.0;  ///< longest stretch outside the band by the margin
  double longest_excess_at_s = 0.0;
  double peak_excess_nm = 0.0;
  int bins_used = 0;  ///< angle bins with enough settled sliding both ways (>= 2 to judge)
};

/// Strokes must pass a reversal by this much before their samples count
/// (the friction's transition over the dead zone), rad.
inline constexpr double kContactSettleRad = 0.25;

/// `x`, `xd` the joint's input angle and velocity, `tau_in` the proximal
/// torque, sample by sample at times `t`.
ContactCheck check_contact(const std::vector<double>& t, const std::vector<double>& x,
                           const std::vector<double>& xd, const std::vector<double>& tau_in,
                           const ContactCheckConfig& config = {});

/// True when `c` shows contact by `config`'s thresholds; `why` gets the reason.
bool shows_contact(const ContactCheck& c, const ContactCheckConfig& config, std::string* why);

}  // namespace tsmh::estimator
