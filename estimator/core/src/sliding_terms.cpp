#include "estimator/sliding_terms.hpp"

#include <algorithm>
#include <cmath>

namespace tsmh::estimator {
namespace {

// Bounds are what identification searches in; they are wide around the
// paper's values (Do & Phee, docs/friction-model.md) and keep every term physically signed.
constexpr ParamSpec kCoulomb[] = {{"rho1", 1.038, 0.01, 20.0, "level"}};
constexpr ParamSpec kAsymmetry[] = {{"rho2", 0.8904, 0.01, 20.0, "level"}};
constexpr ParamSpec kStribeck[] = {{"mu1", 1.0978, 0.0, 20.0, "level"},
                                   {"kappa1", 6.1264, 0.0, 100.0, "s/rad"}};
constexpr ParamSpec kAcceleration[] = {{"mu2", 0.0458, 0.0, 10.0, "level"},
                                       {"kappa2", 0.0269, 0.0, 10.0, "s^2/rad"},
                                       {"mu3", 0.145, 0.0, 10.0, "level"},
                                       {"kappa3", 13.248, 0.0, 200.0, "s/rad"},
                                       {"kappa4", 6.0297, 0.01, 200.0, "rad/s^2"}};
constexpr ParamSpec kReversal[] = {{"lambda", 0.2, 0.0, 2.0, "rad/s"}};
constexpr ParamSpec kViscous[] = {{"c_v", 0.0, 0.0, 20.0, "level s/rad"}};
constexpr ParamSpec kLoad[] = {{"c_load", 0.0, -1.0, 5.0, "level/N"}};
constexpr ParamSpec kPosition[] = {{"p1", 0.0, -10.0, 10.0, "level/rad"},
                                   {"p2", 0.0, -10.0, 10.0, "level/rad^2"}};
constexpr ParamSpec kTime[] = {{"drift", 0.0, -1.0, 1.0, "level/s"},
                               {"step", 0.0, -20.0, 20.0, "level"},
                               {"t_step", 0.0, 0.0, 1e6, "s"},
                               {"t0", 0.0, -1e9, 1e9, "s", false}};

constexpr ParamSpec kRipple[] = {{"a_sin", 0.0, -10.0, 10.0, "level"},
                                 {"a_cos", 0.0, -10.0, 10.0, "level"},
                                 {"wavenumber", 6.0, 0.3, 500.0, "1/rad"}};
constexpr ParamSpec kBump[] = {{"amp", 0.0, -10.0, 10.0, "level"},
                               {"center", 0.0, -100.0, 100.0, "rad"},
                               {"width", 0.1, 0.005, 10.0, "rad"}};
constexpr ParamSpec kLoadSat[] = {{"c_sat", 0.0, -1.0, 5.0, "level/N"},
                                  {"l_sat", 10.0, 0.1, 1000.0, "N"}};

constexpr ParamSpec kLoadScale[] = {{"k_abs", 0.0, -0.5, 0.5, "1/N"},
                                    {"k_signed", 0.0, -0.5, 0.5, "1/N"},
                                    {"k_along", 0.0, -0.5, 0.5, "1/N"}};
constexpr ParamSpec kTensionScale[] = {{"k_t", 0.0, -0.5, 0.5, "1/N"},
                                       {"t_ref", 20.0, -1e6, 1e6, "N", false}};

constexpr ParamSpec kElements[] = {{"w2", 0.2, 0.0, 0.9, ""}, {"r2", 10.0, 0.05, 200.0, ""}};

constexpr TermInfo kCatalog[] = {
    {TermKind::kCoulomb, "coulomb", "Coulomb sliding level rho1 (eqs. 6, 7)",
     "everywhere in sliding", kCoulomb},
    {TermKind::kDirectionAsymmetry, "direction_asymmetry",
     "different sliding level for negative velocity, rho2 (eqs. 9-11): unequal sheaths and "
     "pretensions",
     "sliding with xd < 0 vs xd > 0", kAsymmetry},
    {TermKind::kStribeck, "stribeck",
     "Stribeck rise of friction at low speed, mu1 e^(-kappa1 |xd|)", "low |xd|, both directions",
     kStribeck},
    {TermKind::kAccelerationDependence, "acceleration_dependence",
     "different levels accelerating vs decelerating (mu2 terms of eqs. 6-7, mu3 of eqs. 9-10)",
     "same speed, opposite sign of xdd", kAcceleration},
    {TermKind::kReversalOffset, "reversal_offset",
     "offset lambda of the hysteresis near zero velocity, g = xd + lambda sgn(xdd) (eq. 4)",
     "near velocity reversals", kReversal},
    {TermKind::kViscous, "viscous", "viscous drag, friction grows linearly with speed",
     "high |xd|, both directions", kViscous},
    {TermKind::kLoadDependent, "load_dependent",
     "capstan effect: friction grows with the transmitted load (tension)",
     "high |tau_in|, in contact", kLoad},
    {TermKind::kPositionDependent, "position_dependent",
     "friction varies with the pulley angle (wrap changes along the stroke)",
     "one end of the stroke vs the other", kPosition},
    {TermKind::kTimeVarying, "time_varying",
     "friction drifts or steps over time (sheath re-routed, wear, temperature)",
     "late vs early in the recording", kTime},
    {TermKind::kPositionRipple, "position_ripple",
     "friction varies periodically with the pulley angle (a ripple along the stroke)",
     "periodic in the angle", kRipple, "position_dependent"},
    {TermKind::kPositionBump, "position_bump",
     "friction rises or falls locally around one angle (a kink in the sheath)",
     "around one angle of the stroke", kBump, "position_dependent"},
    {TermKind::kLoadSaturating, "load_saturating",
     "capstan effect that levels off: friction grows with the load up to a limit",
     "high |tau_in|, in contact", kLoadSat, "load_dependent"},
    {TermKind::kHysteresisElements, "hysteresis_elements",
     "hysteresis with memory: a second element of eq. (4)'s state, share w2 at rate r2 theta; "
     "after a small reversal the friction returns along a stiffer path than one state allows",
     "after small reversals, around each reversal's transition", kElements},
    {TermKind::kLoadScaling, "load_scaling",
     "capstan effect on the distal load: the whole friction scales with the load the tendons "
     "carry to the tip, Ff x (1 + k_abs |D| + k_signed D + k_along sgn(F) D), D = tau_out / R "
     "(k_signed: sheaths bent unequally; k_along: the load raises the tension of the tendon "
     "that pulls against the friction)",
     "in contact, growing with the tip load", kLoadScale, "load_dependent"},
    {TermKind::kTensionScaling, "tension_scaling",
     "the whole friction scales with the tension the tendons carry, Ff x (1 + k_t (T - t_ref)), "
     "T = (T1 + T3) / 2",
     "where the mean tendon tension differs from its mean", kTensionScale, "tension_dependent"},
};

}  // namespace

std::span<const TermInfo> term_catalog() {
  return kCatalog;
}

const TermInfo& term_info(TermKind kind) {
  return kCatalog[static_cast<int>(kind)];
}

std::string_view term_family(TermKind kind) {
  const auto& info = term_info(kind);
  return info.family.empty() ? info.name : info.family;
}

std::optional<TermKind> term_kind_from_name(std::string_view name) {
  for (const auto& info : kCatalog) {
    if (info.name == name) return info.kind;
  }
  return std::nullopt;
}

double term_level(const Term& term, const Motion& m, bool asymmetric) noexcept {
  const auto& p = term.p;
  const bool negative = negative_branch(m.xd);
  const double speed = std::fabs(m.xd);
  switch (term.kind) {
    case TermKind::kCoulomb:
      return (negative && asymmetric) ? 0.0 : p[0];
    case TermKind::kDirectionAsymmetry:
      return negative ? p[0] : 0.0;
    case TermKind::kStribeck:
      return stribeck_level(p[0], p[1], speed);
    case TermKind::kAccelerationDependence:
      return acceleration_level(p, m, negative, speed);
    case TermKind::kReversalOffset:
      return 0.0;  // acts on g, not on Ff
    case TermKind::kViscous:
      return p[0] * speed;
    case TermKind::kLoadDependent:
      return p[0] * m.load;
    case TermKind::kPositionDependent:
      return (p[0] + p[1] * m.x) * m.x;
    case TermKind::kTimeVarying:
      return p[0] * (m.t - p[3]) + (m.t >= p[2] ? p[1] : 0.0);
    case TermKind::kPositionRipple:
      return p[0] * std::sin(p[2] * m.x) + p[1] * std::cos(p[2] * m.x);
    case TermKind::kPositionBump: {
      const double u = (m.x - p[1]) / p[2];
      return p[0] * std::exp(-0.5 * u * u);
    }
    case TermKind::kLoadSaturating:
      return p[0] * p[1] * std::tanh(m.load / p[1]);
    case TermKind::kHysteresisElements:
      return 0.0;  // acts on the state, not on Ff
    case TermKind::kLoadScaling:
    case TermKind::kTensionScaling:
      return 0.0;  // scales the sum (term_scaling)
  }
  return 0.0;
}

double term_scaling(const Term& term, const Motion& m, double friction) noexcept {
  double g = 1.0;
  switch (term.kind) {
    case TermKind::kLoadScaling: {
      const double distal = std::isfinite(m.distal) ? m.distal : m.drive - friction;
      if (!std::isfinite(distal)) return 1.0;
      g = 1.0 + term.p[0] * std::fabs(distal) + term.p[1] * distal +
          term.p[2] * sign_of(friction) * distal;
      break;
    }
    case TermKind::kTensionScaling:
      if (!std::isfinite(m.tension)) return 1.0;
      g = 1.0 + term.p[0] * (m.tension - term.p[1]);
      break;
    default:
      return 1.0;
  }
  return std::clamp(g, kMinScaling, kMaxScaling);
}

double sum_of_term_levels(std::span<const Term> terms, const Motion& m, bool asymmetric) noexcept {
  double level = 0.0;
  for (const auto& t : terms)
    level += term_level(t, m, asymmetric);
  return level;
}

}  // namespace tsmh::estimator
