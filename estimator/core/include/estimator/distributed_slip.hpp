#pragma once
// Distributed slip: the friction of a sheath whose slip spreads along its
// length, as a family of elasto-slide (play, Maxwell-slip, Prandtl-Ishlinskii)
// elements plus a smoothed-velocity sliding term, with copies of every basis
// function scaled by the tension the tendons carry.
//
// Each element i is a spring of break displacement r_i (its "width") in series
// with a slider: its normalised deflection e_i follows the input angle x,
//   e_i <- clamp(e_i + dx / r_i, -k_neg, k_pos)
// and carries the force w_i e_i (w_i its break force). Widths are spaced
// log-uniformly from width_min to width_max: stiff elements (short widths)
// slip first after a reversal, compliant ones last, so the transition after a
// reversal is the sum of many saturations (a sheath whose segments slip one
// after the other) instead of one Bouc-Wen curve. The output of one element
// is exactly a Prandtl-Ishlinskii play operator's: y_i = x - r_i e_i.
//
// The sliding part is a function of the velocity alone, smoothed at rest:
//   s = tanh(xd / smoothing)
//   phi = [max(s, 0), min(s, 0), e^(-|xd| / stribeck_speed) s, xd]
//   (Coulomb for each direction, a Stribeck rise, viscous drag).
//
// The basis phi_k (elements, then the four sliding functions) enters the
// friction linearly:
//   F = sum_k phi_k (w_k + t_k (T - T_ref) + d_k u + l_k |D|)
// T: the mean of the two proximal tensions (T1 + T3) / 2: the pretension the
// pair carries. It does not contain the tip load (a tip torque raises one
// tension and lowers the other) and it contains only the difference of the
// two sheaths' frictions, not their sum, so a tension copy cannot read the
// friction itself from its input (unlike |tau_in| / R, which is the friction
// in free motion).
// u: the signed proximal drive tau_in / R = T1 - T3 (measured online, as T).
// With the tension copies it makes each tendon's friction scale with its own
// tension: T1 = T + u/2, T3 = T - u/2, and a sheath's capstan gives, while
// it slides, F_j = c_j T_j with c_j = 1 - e^(-mu_j wrap_j) for the tendon
// pulled and e^(mu_j wrap_j) - 1 for the one released. Two sheaths bent
// differently have different c_j, so the friction depends on which tendon
// carries the load, not only on its size; a slack tendon (T_j -> 0) takes
// its sheath's friction with it. The proximal tensions are what the sheath's
// friction is proportional to, so the relation is explicit (no solve), and
// u's noise enters only through the small d_k. In free motion u is the
// friction itself (D = 0): the d_k then only rescale the w_k, so free-motion
// data cannot tell them apart; data with tip loads of both signs can.
// D: the distal load tau_out / R = tau_in / R - F, the capstan effect of the
// load the tendon transmits to the tip. It contains F, so the model solves
// F = A + B |u - F| exactly (u = tau_in / R): with |B| < 1 the right side's
// slope is below one and there is one solution, on the branch u >= A or
// u < A. In free motion D = 0: free-motion data cannot determine the l_k.
//
// Per-tendon widths (`tendon_widths`): a sheath's presliding follows the
// tension its tendon carries. After a reversal the slip spreads from the
// pulled end until the friction has turned; the friction per length is
// mu T kappa, so both the break force and the displacement it takes to
// reach it grow with the tendon's tension T_j, while the stiffness (the
// tendon's EA over the slipping length) does not. The elements then come
// as two families, one per tendon (elements 0 .. n-1 for tendon 1, which
// pulls x positive, n .. 2n-1 for tendon 2), each element a constant
// stiffness whose saturation scales with g_j = max(T_j, 0) / T_ref:
//   e_i <- clamp(e_i + dx / r_i, -k_neg g_j, k_pos g_j)
// with T_1 = T + u/2, T_2 = T - u/2 (the proximal tensions). A slack tendon
// (T_j <= 0) clamps its family to zero: its sheath transmits no friction. The
// break force w_i g_j then follows the tension by itself; the copies add to
// that. Without measured tensions (T or u NaN) g_j = 1 and the two
// families are the plain elements twice. At T_j = T_ref the model is the
// plain one with the two families' weights summed.
//
// Coulomb as a state (`coulomb_play`): tanh(xd / smoothing) in the two
// Coulomb functions vanishes when the input stops, while a stuck sheath
// holds the friction it had when it stopped (the proximal angle still, the
// segments stuck). With coulomb_play the two Coulomb functions read a play
// of the narrowest element's width instead,
//   c <- clamp(c + dx / width_min, -1, 1),  phi = [max(c, 0), min(c, 0), ...]
// so at rest they keep their last value, as the elements do; the Stribeck
// rise and the viscous drag stay functions of the velocity (they vanish at
// rest). The fit cannot tell the two apart on data without holds (a
// multisine), and they differ wherever the input stops.
//
// Slip driven from the tip (`distal_elements`): the elements above follow
// the input angle, as if the tendon were rigid. A tendon in a sheath is not:
// when the tip's load changes while the input stands still, the tendon
// stretches, its distal segments slide, and the friction they carry turns
// from that end of the sheath, which no function of x_in can follow. The
// distal family is a second set of elements driven by the distal (joint)
// angle x_out from a joint encoder (same scale as x_in: pulleys of equal
// radius), with the same spread of widths:
//   d_j <- clamp(d_j + dx_out / r_j, -k_neg, k_pos)
// A joint's motion moves both ends alike, so the two families add up there;
// they differ by the stretch x_out - x_in, and only the distal one turns
// when the tip moves alone. Without a joint encoder (x_out NaN) the family
// follows x_in (a rigid tendon), and a change of source (the encoder appears
// or drops out) re-anchors it without a step. With `distal_position2` the
// family is split in two, each half driven at its own place along the sheath.
//
// No sign of the acceleration appears anywhere.

#include <array>
#include <cstddef>

#include "estimator/motion.hpp"

namespace tsmh::estimator {

/// Most elements a model may have (the state is a fixed-size array).
inline constexpr std::size_t kMaxSlipElements = 24;
/// The sliding basis functions after the elements.
inline constexpr std::size_t kSlidingFunctions = 4;
/// Index of the first sliding function in the weight arrays (fixed, so that
/// the element count can change without moving them).
inline constexpr std::size_t kSlidingIndex = kMaxSlipElements;
/// Most elements of the distal family (driven by x_out).
inline constexpr std::size_t kMaxDistalElements = 12;
/// Index of the distal family's first element in the weight arrays, after
/// the sliding functions (so that files without it keep their layout).
inline constexpr std::size_t kDistalIndex = kSlidingIndex + kSlidingFunctions;
inline constexpr std::size_t kMaxSlipBasis = kDistalIndex + kMaxDistalElements;
/// Bound on |dF/d|D|| the model uses, so that the distal load equation keeps
/// one solution (the load weights are clamped to it at run time).
inline constexpr double kMaxLoadSlope = 0.9;
/// Bound on each drive weight |d_k|: a sheath's capstan share of its
/// tendon's tension, 1 - e^(-mu wrap) or e^(mu wrap) - 1, stays below 1 for
/// wraps up to mu wrap = ln 2.
inline constexpr double kMaxDriveSlope = 1.0;

struct DistributedSlipSpec {
  bool enabled = false;
  int elements = 14;            ///< 1 .. kMaxSlipElements
  double width_min = 1e-3;      ///< rad, the stiffest element's break displacement
  double width_max = 0.3;       ///< rad, the most compliant one's (>= width_min)
  double smoothing = 0.01;      ///< rad/s, tanh(xd / smoothing) in the sliding part
  double stribeck_speed = 0.1;  ///< rad/s, decay of the Stribeck rise
  double tension_ref = 20.0;    ///< N, the mean tension at which the tension copies add 0
  bool tension_copies = false;  ///< the t_k are part of the model
  bool load_copies = false;     ///< the l_k are part of the model
  bool drive_copies = false;    ///< the d_k are part of the model
  /// Two element families, one per tendon, whose saturation scales with
  /// that tendon's tension (see the header); `elements` is per family.
  bool tendon_widths = false;
  /// The Coulomb functions read a play of width width_min (their state
  /// holds at rest) instead of tanh(xd / smoothing) (see the header).
  bool coulomb_play = false;
  /// Elements driven by the distal angle x_out (0: none; see the header).
  int distal_elements = 0;
  /// Where along the sheath the distal family sits, as the share of the
  /// distal angle in its drive x_in + a (x_out - x_in): 1 at the tip, 0.5
  /// halfway (a uniformly stretched tendon moves there by half the stretch).
  double distal_position = 1.0;
  /// A second position (0: none). With it the distal family comes as two
  /// sub-families: elements 0 .. ceil(n/2)-1 at distal_position, the rest
  /// at distal_position2, each spanning the same widths: the sheath's slip
  /// at two places along it (a stretch that is not uniform).
  double distal_position2 = 0.0;
  /// Weights per basis function, N: elements 0 .. elements-1, then the sliding
  /// functions at kSlidingIndex + {0: coulomb +, 1: coulomb -, 2: stribeck,
  /// 3: viscous (N s/rad)}, then the distal family from kDistalIndex. Unused
  /// entries are 0.
  std::array<double, kMaxSlipBasis> weight{};
  std::array<double, kMaxSlipBasis> tension_weight{};  ///< per N of (T - T_ref)
  std::array<double, kMaxSlipBasis> load_weight{};     ///< per N of |D|
  std::array<double, kMaxSlipBasis> drive_weight{};    ///< per N of u (signed)

  /// Elements in the state: `elements`, twice with per-tendon widths.
  std::size_t element_count() const {
    return static_cast<std::size_t>(elements) * (tendon_widths ? 2 : 1);
  }
  std::size_t distal_count() const { return static_cast<std::size_t>(distal_elements); }
  /// Elements of the first sub-family (all of them with one position).
  std::size_t distal_first_count() const {
    return distal_position2 > 0.0 ? (distal_count() + 1) / 2 : distal_count();
  }
  /// The indices of the basis functions in use, in order (elements, sliding,
  /// distal elements).
  std::size_t basis_count() const { return element_count() + kSlidingFunctions + distal_count(); }
  std::size_t basis_index(std::size_t k) const {
    const std::size_t n = element_count();
    if (k < n) return k;
    if (k < n + kSlidingFunctions) return kSlidingIndex + (k - n);
    return kDistalIndex + (k - n - kSlidingFunctions);
  }
  /// Width of element i at the reference tension (log-uniform from width_min
  /// to width_max; each family spans the same widths).
  double width(std::size_t i) const;
  /// Width of distal element j (log-uniform over the same span, per sub-family).
  double distal_width(std::size_t j) const;
};

/// The catalog default: 14 elements over 1 mrad .. 0.3 rad, weights that
/// sum to about the paper's sliding level, no copies.
DistributedSlipSpec default_distributed_slip();

/// Name of basis function k of the weight arrays ("e3", "coulomb_positive", ...).
const char* slip_basis_name(std::size_t array_index);

/// Throws std::invalid_argument naming the field ("distributed_slip.width_min: ...").
void validate(const DistributedSlipSpec& spec);

/// The elements' state and the last input angle: what step() changes.
struct SlipState {
  std::array<double, kMaxSlipElements> e{};
  double x_prev = 0.0;
  double coulomb = 0.0;  ///< the Coulomb functions' play, in [-1, 1] (coulomb_play)
  bool started = false;
  std::array<double, kMaxDistalElements> d{};  ///< the distal family's state
  double y_prev = 0.0;                         ///< the angle the distal family last followed
  bool y_measured = false;                     ///< whether that was x_out (else x_in)
};

/// The basis of one sample, weights applied later: phi by array index.
struct SlipBasis {
  std::array<double, kMaxSlipBasis> phi{};
  /// Each element family's saturation scale g_j at this sample (1, 1 without
  /// per-tendon widths).
  std::array<double, 2> scale{1.0, 1.0};
};

/// Precomputed per-spec constants: inverse widths, the level scales.
class SlipKernel {
 public:
  SlipKernel() = default;
  explicit SlipKernel(const DistributedSlipSpec& spec);

  /// Advances the elements to angle x and fills the basis at velocity xd;
  /// `tension` (T) and `drive` (u) set the per-tendon widths' scales (NaN:
  /// the reference tension); `x_out` drives the distal family (NaN: x).
  /// Never allocates; non-finite x, xd are the caller's to refuse.
  void advance(SlipState& s, double x, double xd, double tension, double drive, double x_out,
               SlipBasis& out) const noexcept;
  /// The friction A + B |D| of a basis, solved for the distal load (see the
  /// header): `extra` is friction the rest of the model adds (Bouc-Wen);
  /// `tension` NaN or `drive` NaN turn the respective copies off (the
  /// drive copies and the load copies both need `drive`).
  /// `level` receives the sliding level at this basis: the elements'
  /// saturation plus the magnitude of the sliding functions' friction, N.
  double friction(const SlipBasis& b, double tension, double drive, double extra,
                  double& level) const noexcept;
  /// Sets every element's state to `fraction` of its saturation at mean
  /// tension `tension` (NaN: the reference) (preset); `x_out` anchors the
  /// distal family (NaN: x).
  void preset(SlipState& s, double x, double fraction, double tension, double x_out) const noexcept;
  /// The saturated elements' friction per unit of state (sum of weights).
  double element_capacity(double tension) const noexcept;

  void set_level_scales(double k_positive, double k_negative) noexcept {
    k_pos_ = k_positive;
    k_neg_ = k_negative;
  }
  const DistributedSlipSpec& spec() const { return spec_; }

 private:
  double weight(std::size_t idx, double tension_offset) const noexcept {
    return spec_.weight[idx] + tension_offset * spec_.tension_weight[idx];
  }
  DistributedSlipSpec spec_;
  std::array<double, kMaxSlipElements> inv_width_{};
  std::array<double, kMaxDistalElements> inv_distal_width_{};
  double distal_ratio_ = 0.0;  ///< distal_position2 / distal_position
  double inv_smoothing_ = 1.0, inv_stribeck_ = 1.0;
  double inv_tension_ref_ = 0.0;  ///< 1 / tension_ref (0: no per-tendon scaling)
  /// Each family's saturation scale g_j = max(T_j, 0) / T_ref with
  /// T_1,2 = T +- u/2 (1, 1 without per-tendon widths or a measured T; u NaN
  /// counts as 0, both tendons at the mean tension).
  std::array<double, 2> family_scales(double tension, double drive) const noexcept;
  double k_pos_ = 1.0, k_neg_ = 1.0;
};

}  // namespace tsmh::estimator
