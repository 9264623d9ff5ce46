#pragma once
// The sliding level Ff of the tendon-sheath model (eqs. 5-11) as a sum of
// named terms. The paper's Ff is one configuration of this catalog
// (coulomb + direction_asymmetry + stribeck + acceleration_dependence, with
// reversal_offset driving g in eq. 4); the model-gap workflow adds further
// physical effects (viscous, load_dependent, ...) without a new class.
//
// Branch rule at the boundary xd = 0, which eq. (5) puts in both branches:
// xd >= 0 takes the positive-velocity branch (S+v1 / S+v2), xd < 0 the
// negative one (S-v). Tests pin this down.

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "estimator/motion.hpp"

namespace tsmh::estimator {

enum class TermKind : std::uint8_t {
  kCoulomb,                 ///< rho1: the level (both directions unless direction_asymmetry)
  kDirectionAsymmetry,      ///< rho2: the level for xd < 0, replacing rho1 there
  kStribeck,                ///< mu1 e^(-kappa1 |xd|)
  kAccelerationDependence,  ///< eqs. 6-10: +-mu2 (1 - e^-|kappa2 xdd|) and +-mu3 e^-f2
  kReversalOffset,          ///< lambda in g = xd + lambda sgn(xdd) (eq. 4); adds nothing to Ff
  kViscous,                 ///< c_v |xd|: friction grows with speed
  kLoadDependent,           ///< c_load |tau_in|/R: capstan, friction grows with tension
  kPositionDependent,       ///< p1 x + p2 x^2: friction varies along the stroke
  kTimeVarying,             ///< drift (t - t0) + step [t >= t_step]: sheath re-routed, wear
  // Further forms of the same physical effects (real effects do not come in
  // one form). Each belongs to a family (TermInfo::family), the name
  // under which tsm gap reports it.
  kPositionRipple,  ///< a sin(k x) + b cos(k x): periodic friction along the stroke (family
                    ///< position)
  kPositionBump,    ///< amp exp(-((x - center)/width)^2 / 2): a local kink in the sheath
  kLoadSaturating,  ///< c_sat l_sat tanh(load / l_sat): capstan growth that levels off
  /// A second element of eq. (4)'s state with rate r2 theta and share w2 of
  /// the friction (the first: rate theta, share 1 - w2); adds nothing to Ff.
  /// Memory: after a small reversal the stiff element returns at once while
  /// the other keeps its state, as a capstan's stuck sheath segments do.
  kHysteresisElements,
  // Multiplicative forms: they add nothing to the sum of the terms but scale
  // it (Ff = (sum of the other terms) x g), so a friction that grows with
  // the tension its tendon carries grows in proportion to itself, as a
  // capstan's does. Both read physical quantities that do not contain the
  // friction: the distal load and the mean proximal tension.
  /// g = 1 + k_abs |D| + k_signed D + k_along sgn(F) D, D = tau_out / R the
  /// distal load, which the model takes as drive - F (tau_in / R less its
  /// own last friction F); k_signed: two sheaths bent unequally carry the
  /// load's tension unequally; k_along: the load adds to the tension of the
  /// tendon that pulls against the friction (family load_dependent).
  kLoadScaling,
  /// g = 1 + k_t (T - t_ref), T = (T1 + T3) / 2 the mean proximal tension,
  /// t_ref its mean over the data (family tension_dependent).
  kTensionScaling,
};

inline constexpr int kMaxTermParams = 5;

struct ParamSpec {
  std::string_view name;
  double default_value;
  double lower;
  double upper;
  std::string_view unit;
  bool identified = true;  ///< false: set from the data (e.g. a time origin), never fitted
};

struct TermInfo {
  TermKind kind;
  std::string_view name;     ///< stable id, used in YAML and in gap reports
  std::string_view meaning;  ///< the physical effect, one line
  std::string_view where;    ///< where in the data its absence shows
  std::span<const ParamSpec> params;
  /// The physical effect this term is a form of (tsm gap names effects by
  /// family); empty: the term's own name.
  std::string_view family = {};
};

/// The family name of a term: its `family`, or its own name.
std::string_view term_family(TermKind kind);

/// The whole catalog, in declaration order of TermKind.
std::span<const TermInfo> term_catalog();
const TermInfo& term_info(TermKind kind);
std::optional<TermKind> term_kind_from_name(std::string_view name);

struct Term {
  TermKind kind = TermKind::kCoulomb;
  std::array<double, kMaxTermParams> p{};  ///< in the order of term_info(kind).params
};

/// Contribution of one term to the sliding level Ff at motion `m`.
/// `asymmetric` tells the coulomb term that direction_asymmetry is present,
/// so rho1 only applies to the positive branch.
double term_level(const Term& term, const Motion& m, bool asymmetric) noexcept;

/// The sum of the terms' contributions, in their order: Ff before the floor.
/// The reference for TsmFrictionModel's flat evaluation of the paper's terms.
double sum_of_term_levels(std::span<const Term> terms, const Motion& m, bool asymmetric) noexcept;

/// True for the terms that scale the sum instead of adding to it.
constexpr bool is_multiplicative(TermKind kind) {
  return kind == TermKind::kLoadScaling || kind == TermKind::kTensionScaling;
}

/// The factor g of a multiplicative term at motion `m`, where `friction` is
/// the model's friction before this step (the distal load is drive -
/// friction); 1 when its quantity is unknown (NaN), and kept within
/// [kMinScaling, kMaxScaling] so that a fitted slope cannot turn the level
/// over or run it away outside the data. 1 for any other term.
inline constexpr double kMinScaling = 0.1;
inline constexpr double kMaxScaling = 10.0;
double term_scaling(const Term& term, const Motion& m, double friction) noexcept;

/// True when xd takes the negative-velocity branch (xd < 0; xd = 0 is positive).
constexpr bool negative_branch(double xd) {
  return xd < 0.0;
}

// The two formulas of the paper's Ff that need exp(), shared by term_level()
// and TsmFrictionModel's flat evaluation so that both compute the same
// operations in the same order (bit-identical results).

/// stribeck: mu1 e^(-kappa1 |xd|); `speed` is |xd|.
inline double stribeck_level(double mu1, double kappa1, double speed) noexcept {
  return mu1 * std::exp(-kappa1 * speed);
}

/// acceleration_dependence (eqs. 6-11) with p = {mu2, kappa2, mu3, kappa3, kappa4}.
inline double acceleration_level(const std::array<double, kMaxTermParams>& p, const Motion& m,
                                 bool negative, double speed) noexcept {
  if (!negative) {
    // eqs. (6)/(7): + when accelerating (xdd > 0), - when decelerating;
    // at xdd = 0 both give 0, so the shared boundary is consistent.
    const double mag = p[0] * (1.0 - std::exp(-std::fabs(p[1] * m.xdd)));
    return m.acc_sign * mag;
  }
  // eqs. (9)-(11). Eq. (8)'s compact form writes "+ sgn(xdd) mu3 e^-f2",
  // which contradicts its own sub-cases: (9) has +mu3 for xdd < 0 and (10)
  // has -mu3 for xdd > 0. We follow (9)-(11): s = -sgn(xdd).
  const double s = -m.acc_sign;
  if (s == 0.0) return 0.0;
  const double f2 = p[3] * speed / (std::fabs(m.xdd) + p[4]);
  return s * p[2] * std::exp(-f2);
}

}  // namespace tsmh::estimator
