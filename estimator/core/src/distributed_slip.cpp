#include "estimator/distributed_slip.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tsmh::estimator {

namespace {
// Element i of n, log-uniform from lo to hi: every family spans the same widths.
double log_spaced(double lo, double hi, std::size_t i, int n) {
  if (n <= 1) return lo;
  const double f = static_cast<double>(i) / static_cast<double>(n - 1);
  return lo * std::pow(hi / lo, f);
}
}  // namespace

double DistributedSlipSpec::width(std::size_t i) const {
  const std::size_t n = static_cast<std::size_t>(std::max(elements, 1));
  return log_spaced(width_min, width_max, i % n, elements);
}

double DistributedSlipSpec::distal_width(std::size_t j) const {
  if (distal_position2 > 0.0) {
    const std::size_t n1 = distal_first_count();
    return j < n1 ? log_spaced(width_min, width_max, j, static_cast<int>(n1))
                  : log_spaced(width_min, width_max, j - n1, static_cast<int>(distal_count() - n1));
  }
  return log_spaced(width_min, width_max, j, distal_elements);
}

DistributedSlipSpec default_distributed_slip() {
  DistributedSlipSpec s;
  s.enabled = true;
  // About the paper's sliding level (gamma rho1 ~ 10 N): 7 N over the
  // elements, 3 N of smoothed Coulomb, a small Stribeck rise.
  for (int i = 0; i < s.elements; ++i)
    s.weight[static_cast<std::size_t>(i)] = 0.5;
  s.weight[kSlidingIndex + 0] = 3.0;
  s.weight[kSlidingIndex + 1] = 3.0;
  s.weight[kSlidingIndex + 2] = 1.0;
  return s;
}

const char* slip_basis_name(std::size_t idx) {
  static constexpr const char* kSliding[] = {"coulomb_positive", "coulomb_negative", "stribeck",
                                             "viscous"};
  static constexpr const char* kElements[] = {
      "e1",  "e2",  "e3",  "e4",  "e5",  "e6",  "e7",  "e8",  "e9",  "e10", "e11", "e12",
      "e13", "e14", "e15", "e16", "e17", "e18", "e19", "e20", "e21", "e22", "e23", "e24"};
  static constexpr const char* kDistal[] = {"d1", "d2", "d3", "d4",  "d5",  "d6",
                                            "d7", "d8", "d9", "d10", "d11", "d12"};
  static_assert(std::size(kElements) == kMaxSlipElements);
  static_assert(std::size(kDistal) == kMaxDistalElements);
  if (idx >= kDistalIndex) return kDistal[idx - kDistalIndex];
  return idx < kSlidingIndex ? kElements[idx] : kSliding[idx - kSlidingIndex];
}

void validate(const DistributedSlipSpec& s) {
  if (!s.enabled) return;
  const auto bad = [](const std::string& field, const std::string& why) {
    throw std::invalid_argument("distributed_slip." + field + ": " + why);
  };
  const auto positive = [&](const char* field, double v) {
    if (!std::isfinite(v) || !(v > 0.0)) bad(field, "must be a finite number > 0");
  };
  if (s.elements < 1 || s.elements > static_cast<int>(kMaxSlipElements))
    bad("elements", "must be 1 .. " + std::to_string(kMaxSlipElements));
  if (s.tendon_widths && s.element_count() > kMaxSlipElements)
    bad("elements", "must be 1 .. " + std::to_string(kMaxSlipElements / 2) +
                        " with tendon_widths (one family per tendon)");
  if (s.distal_elements < 0 || s.distal_elements > static_cast<int>(kMaxDistalElements))
    bad("distal_elements", "must be 0 .. " + std::to_string(kMaxDistalElements));
  if (!(s.distal_position > 0.0 && s.distal_position <= 1.0))
    bad("distal_position", "must be a number in (0, 1]");
  if (!(s.distal_position2 == 0.0 || (s.distal_position2 > 0.0 && s.distal_position2 <= 1.0)))
    bad("distal_position2", "must be 0 (one position) or a number in (0, 1]");
  if (s.distal_position2 > 0.0 && s.distal_elements < 2)
    bad("distal_position2", "needs distal_elements >= 2 (one sub-family per position)");
  if (s.distal_position2 > 0.0 && s.distal_position2 == s.distal_position)
    bad("distal_position2", "must differ from distal_position");
  positive("width_min", s.width_min);
  positive("width_max", s.width_max);
  if (s.width_max < s.width_min) bad("width_max", "must be >= width_min");
  if (s.width_max > 10.0) bad("width_max", "must be <= 10 rad");
  positive("smoothing", s.smoothing);
  positive("stribeck_speed", s.stribeck_speed);
  if (!std::isfinite(s.tension_ref)) bad("tension_ref", "must be a finite number");
  for (std::size_t k = 0; k < s.basis_count(); ++k) {
    const std::size_t idx = s.basis_index(k);
    const std::string name = slip_basis_name(idx);
    if (!std::isfinite(s.weight[idx])) bad("weights." + name, "must be a finite number");
    if ((idx < kSlidingIndex + 3 || idx >= kDistalIndex) && s.weight[idx] < 0.0)
      bad("weights." + name, "must be >= 0 (a negative break force is not passive)");
    if (!std::isfinite(s.tension_weight[idx]))
      bad("tension_weights." + name, "must be a finite number");
    if (!std::isfinite(s.drive_weight[idx]) || std::fabs(s.drive_weight[idx]) > kMaxDriveSlope)
      bad("drive_weights." + name, "must be a finite number within +-1");
    if (!std::isfinite(s.load_weight[idx]) || std::fabs(s.load_weight[idx]) > kMaxLoadSlope)
      bad("load_weights." + name, "must be a finite number within +-0.9");
  }
}

SlipKernel::SlipKernel(const DistributedSlipSpec& spec) : spec_(spec) {
  validate(spec_);
  for (std::size_t i = 0; i < spec_.element_count(); ++i)
    inv_width_[i] = 1.0 / spec_.width(i);
  for (std::size_t j = 0; j < spec_.distal_count(); ++j)
    inv_distal_width_[j] = 1.0 / spec_.distal_width(j);
  distal_ratio_ = spec_.distal_position2 / spec_.distal_position;
  inv_tension_ref_ = spec_.tension_ref > 0.0 ? 1.0 / spec_.tension_ref : 0.0;
  inv_smoothing_ = 1.0 / spec_.smoothing;
  inv_stribeck_ = 1.0 / spec_.stribeck_speed;
  // Entries beyond the copies in use are zero, so the sums below need no flags.
  if (!spec_.tension_copies) spec_.tension_weight.fill(0.0);
  if (!spec_.load_copies) spec_.load_weight.fill(0.0);
  if (!spec_.drive_copies) spec_.drive_weight.fill(0.0);
}

void SlipKernel::advance(SlipState& s, double x, double xd, double tension, double drive,
                         double x_out, SlipBasis& out) const noexcept {
  const double dx = s.started ? x - s.x_prev : 0.0;
  if (spec_.distal_elements > 0) {
    // The distal family follows x_out, or x without a joint encoder; a
    // change of source re-anchors it (the two angles differ by the stretch).
    const bool measured = std::isfinite(x_out);
    const double y = measured ? x + spec_.distal_position * (x_out - x) : x;
    const bool same = s.started && measured == s.y_measured;
    const double dy = same ? y - s.y_prev : 0.0;
    // The second sub-family's angle is x + a2 (x_out - x); its last value
    // follows from the first one's (a1 > 0), so the state stays as it is.
    const double dy2 = same && spec_.distal_position2 > 0.0
                           ? dx + distal_ratio_ * ((y - x) - (s.y_prev - s.x_prev))
                           : dy;
    s.y_prev = y;
    s.y_measured = measured;
    const std::size_t n1 = spec_.distal_first_count();
    for (std::size_t j = 0; j < spec_.distal_count(); ++j) {
      const double step = j < n1 ? dy : dy2;
      const double d = std::min(std::max(s.d[j] + step * inv_distal_width_[j], -k_neg_), k_pos_);
      s.d[j] = d;
      out.phi[kDistalIndex + j] = d;
    }
  }
  s.x_prev = x;
  s.started = true;
  const std::size_t n = static_cast<std::size_t>(spec_.elements);
  out.scale = family_scales(tension, drive);
  const std::size_t families = spec_.tendon_widths ? 2 : 1;
  for (std::size_t f = 0; f < families; ++f) {
    const double lo = -k_neg_ * out.scale[f], hi = k_pos_ * out.scale[f];
    for (std::size_t i = f * n; i < (f + 1) * n; ++i) {
      const double e = std::min(std::max(s.e[i] + dx * inv_width_[i], lo), hi);
      s.e[i] = e;
      out.phi[i] = e;
    }
  }
  const double smooth = std::tanh(xd * inv_smoothing_);
  const double k = xd < 0.0 ? k_neg_ : k_pos_;
  if (spec_.coulomb_play) {
    // Like an element: a level scale bounds the state, so it changes the
    // level reached by motion and leaves the friction of the instant.
    s.coulomb = std::clamp(s.coulomb + dx * inv_width_[0], -k_neg_, k_pos_);
    out.phi[kSlidingIndex + 0] = std::max(s.coulomb, 0.0);
    out.phi[kSlidingIndex + 1] = std::min(s.coulomb, 0.0);
  } else {
    out.phi[kSlidingIndex + 0] = k_pos_ * std::max(smooth, 0.0);
    out.phi[kSlidingIndex + 1] = k_neg_ * std::min(smooth, 0.0);
  }
  out.phi[kSlidingIndex + 2] = k * std::exp(-std::fabs(xd) * inv_stribeck_) * smooth;
  out.phi[kSlidingIndex + 3] = k * xd;
}

double SlipKernel::friction(const SlipBasis& b, double tension, double drive, double extra,
                            double& level) const noexcept {
  const double dt = std::isfinite(tension) ? tension - spec_.tension_ref : 0.0;
  const std::size_t n = spec_.element_count();
  const std::size_t per_family = static_cast<std::size_t>(spec_.elements);
  // The drive copies scale like the tension copies (per N of u); without a
  // measured drive they add nothing.
  const double u = std::isfinite(drive) ? drive : 0.0;
  double elements = 0.0, capacity = 0.0, sliding = 0.0, slope = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weight(i, dt) + u * spec_.drive_weight[i];
    elements += b.phi[i] * w;
    capacity += w * b.scale[i < per_family ? 0 : 1];
    slope += b.phi[i] * spec_.load_weight[i];
  }
  for (std::size_t i = kSlidingIndex; i < kDistalIndex; ++i) {
    sliding += b.phi[i] * (weight(i, dt) + u * spec_.drive_weight[i]);
    slope += b.phi[i] * spec_.load_weight[i];
  }
  for (std::size_t i = kDistalIndex; i < kDistalIndex + spec_.distal_count(); ++i) {
    const double w = weight(i, dt) + u * spec_.drive_weight[i];
    elements += b.phi[i] * w;
    capacity += w;
    slope += b.phi[i] * spec_.load_weight[i];
  }
  const double a = elements + sliding + extra;
  // Where the input slides, the elements saturate at the direction's scale.
  level = (sliding < 0.0 ? k_neg_ : k_pos_) * capacity + std::fabs(sliding);
  if (slope == 0.0 || !std::isfinite(drive)) return a;
  // F = a + B |u - F|, |B| < 1: the root lies where u - F has the sign of u - a.
  const double bs = std::clamp(slope, -kMaxLoadSlope, kMaxLoadSlope);
  return drive >= a ? (a + bs * drive) / (1.0 + bs) : (a - bs * drive) / (1.0 - bs);
}

double SlipKernel::element_capacity(double tension) const noexcept {
  const double dt = std::isfinite(tension) ? tension - spec_.tension_ref : 0.0;
  // At rest both tendons carry about the mean tension (no drive).
  const double g = family_scales(tension, 0.0)[0];
  double sum = 0.0;
  for (std::size_t i = 0; i < spec_.element_count(); ++i)
    sum += weight(i, dt) * g;
  for (std::size_t j = 0; j < spec_.distal_count(); ++j)
    sum += weight(kDistalIndex + j, dt);
  return sum;
}

std::array<double, 2> SlipKernel::family_scales(double tension, double drive) const noexcept {
  if (!spec_.tendon_widths || !std::isfinite(tension) || !(inv_tension_ref_ > 0.0))
    return {1.0, 1.0};
  const double half = std::isfinite(drive) ? 0.5 * drive : 0.0;
  return {std::max(tension + half, 0.0) * inv_tension_ref_,
          std::max(tension - half, 0.0) * inv_tension_ref_};
}

void SlipKernel::preset(SlipState& s, double x, double fraction, double tension,
                        double x_out) const noexcept {
  const double u = std::clamp(fraction, -1.0, 1.0);
  const double level = u >= 0.0 ? u * k_pos_ : u * k_neg_;
  const double e = level * family_scales(tension, 0.0)[0];
  for (std::size_t i = 0; i < spec_.element_count(); ++i)
    s.e[i] = e;
  for (std::size_t j = 0; j < spec_.distal_count(); ++j)
    s.d[j] = level;
  s.y_measured = std::isfinite(x_out);
  s.y_prev = s.y_measured ? x + spec_.distal_position * (x_out - x) : x;
  s.coulomb = level;
  s.x_prev = x;
  s.started = true;
}

}  // namespace tsmh::estimator
