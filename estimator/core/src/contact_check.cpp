#include "estimator/contact_check.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "realtime/quantile.hpp"

namespace tsmh::estimator {
namespace {

constexpr int kBins = 8;
constexpr std::size_t kMinPerSide = 30;  // samples per bin and direction (30 ms at 1 kHz)
// Friction switches between its levels over the dead zone after a reversal
// (the slip front crossing the tendon, ~0.2 rad on the paper's rig); samples
// still in that transition would make the loop's midline look tilted at both
// ends of the stroke, so only samples kContactSettleRad past the last
// reversal count.
constexpr double kSettleRad = kContactSettleRad;
constexpr double kReversalRad = 0.05;  // the angle must retreat this far to count as a reversal

std::string num(double v, int digits = 3) {
  std::ostringstream s;
  s.precision(digits);
  s << v;
  return s.str();
}

}  // namespace

ContactCheck check_contact(const std::vector<double>& t, const std::vector<double>& x,
                           const std::vector<double>& xd, const std::vector<double>& tau_in,
                           const ContactCheckConfig& config) {
  ContactCheck c;
  const std::size_t n = std::min({t.size(), x.size(), xd.size(), tau_in.size()});
  if (n < 2) return c;
  std::vector<double> speed(n);
  for (std::size_t i = 0; i < n; ++i)
    speed[i] = std::fabs(xd[i]);
  const double v_slide = std::max(0.05, 0.2 * realtime::quantile(speed, 0.95));

  // Settled sliding samples: fast enough and far enough past the last
  // reversal. Reversals are found on the angle (it retreats from its running
  // extreme by kReversalRad), not on the velocity's sign: a slave's backlash
  // compensation jerks the motor at each reversal and a differentiated
  // velocity may briefly change sign there without the stroke reversing.
  std::vector<int> dir(n, 0);
  double extreme = x[0], anchor = x[0];
  int heading = 0;  // +1 up, -1 down, 0 not known yet
  for (std::size_t i = 0; i < n; ++i) {
    if (heading >= 0 && x[i] < extreme - kReversalRad) {
      anchor = extreme, heading = -1, extreme = x[i];
    } else if (heading <= 0 && x[i] > extreme + kReversalRad) {
      anchor = extreme, heading = 1, extreme = x[i];
    }
    extreme = heading > 0 ? std::max(extreme, x[i]) : std::min(extreme, x[i]);
    const int now = xd[i] > v_slide ? 1 : (xd[i] < -v_slide ? -1 : 0);
    if (heading != 0 && now == heading && std::fabs(x[i] - anchor) >= kSettleRad) dir[i] = now;
  }
  std::vector<double> xs;
  for (std::size_t i = 0; i < n; ++i)
    if (dir[i] != 0) xs.push_back(x[i]);
  if (xs.size() < 2 * kMinPerSide) return c;
  const double lo = realtime::quantile(xs, 0.02), hi = realtime::quantile(xs, 0.98);
  if (!(hi > lo)) return c;

  std::vector<double> up[kBins], down[kBins];
  for (std::size_t i = 0; i < n; ++i) {
    if (dir[i] == 0 || x[i] < lo || x[i] > hi) continue;
    const int b = std::min(kBins - 1, static_cast<int>((x[i] - lo) / (hi - lo) * kBins));
    (dir[i] > 0 ? up[b] : down[b]).push_back(tau_in[i]);
  }
  std::vector<double> ups, downs, halves;
  double mid_min = INFINITY, mid_max = -INFINITY, at_min = 0.0, at_max = 0.0;
  for (int b = 0; b < kBins; ++b) {
    if (up[b].size() < kMinPerSide || down[b].size() < kMinPerSide) continue;
    const double u = realtime::median(up[b]), d = realtime::median(down[b]);
    ups.push_back(u);
    downs.push_back(d);
    halves.push_back(0.5 * (u - d));
    const double mid = 0.5 * (u + d);
    const double centre = lo + (b + 0.5) * (hi - lo) / kBins;
    if (mid < mid_min) mid_min = mid, at_min = centre;
    if (mid > mid_max) mid_max = mid, at_max = centre;
  }
  c.bins_used = static_cast<int>(halves.size());
  if (c.bins_used < 2) return c;
  c.band_half_width_nm = std::max(0.0, realtime::median(halves));
  c.midline_shift_nm = mid_max - mid_min;
  // Contact pushes one way: name the end where the midline is furthest out.
  c.midline_shift_at_rad = std::fabs(at_max) > std::fabs(at_min) ? at_max : at_min;

  const double level_up = realtime::median(ups), level_down = realtime::median(downs);
  const double margin = config.max_band_excess * c.band_half_width_nm;
  double run_start = 0.0;
  bool in_run = false;
  for (std::size_t i = 0; i < n; ++i) {
    const double excess = std::max({tau_in[i] - level_up, level_down - tau_in[i], 0.0});
    c.peak_excess_nm = std::max(c.peak_excess_nm, excess);
    if (excess > margin) {
      if (!in_run) run_start = t[i], in_run = true;
      if (t[i] - run_start > c.longest_excess_s) {
        c.longest_excess_s = t[i] - run_start;
        c.longest_excess_at_s = run_start;
      }
    } else {
      in_run = false;
    }
  }
  return c;
}

bool shows_contact(const ContactCheck& c, const ContactCheckConfig& config, std::string* why) {
  std::string reason;
  if (c.midline_shift_nm > config.max_midline_shift * c.band_half_width_nm) {
    reason = "the proximal torque's loop shifts by " + num(c.midline_shift_nm) +
             " N m along the stroke (strongest near x_in = " + num(c.midline_shift_at_rad) +
             " rad; free motion stays within " + num(config.max_midline_shift) +
             "x the loop's half-width " + num(c.band_half_width_nm) +
             " N m): a load that grows with position";
  } else if (c.longest_excess_s >= config.max_excess_s) {
    reason = "the proximal torque stays outside the sliding-friction band (half-width " +
             num(c.band_half_width_nm) + " N m) by more than " + num(config.max_band_excess) +
             "x that for " + num(c.longest_excess_s) +
             " s from t = " + num(c.longest_excess_at_s, 6) + " s (peak " + num(c.peak_excess_nm) +
             " N m beyond it): a sustained external load";
  }
  if (why) *why = reason;
  return !reason.empty();
}

}  // namespace tsmh::estimator
