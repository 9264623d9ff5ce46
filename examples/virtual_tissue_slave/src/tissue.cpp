#include "virtual_tissue_slave/tissue.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "field_checks.hpp"

namespace tsmh::virtual_tissue_slave {
namespace {

// Preset stiffnesses, chosen so the joint-space values (lever 3 cm) are
// 0.2 N m/rad (soft) and 1.5 N m/rad (hard): within what the tendon-sheath
// transmission (about 0.5 N m/rad torsional stiffness end to end) can render.
constexpr double kLever = 0.03;
constexpr double kSoft = 0.2 / (kLever * kLever);  // N/m
constexpr double kHard = 1.5 / (kLever * kLever);  // N/m

}  // namespace

std::vector<std::string> tissue_preset_names() {
  return {"none", "soft", "hard", "nodule"};
}

ContactLaw parse_contact_law(std::string_view name) {
  if (name == "kelvin-voigt") return ContactLaw::kKelvinVoigt;
  if (name == "hunt-crossley") return ContactLaw::kHuntCrossley;
  throw std::invalid_argument("unknown contact law '" + std::string(name) +
                              "' (known: kelvin-voigt, hunt-crossley)");
}

std::string_view contact_law_name(ContactLaw law) {
  return law == ContactLaw::kKelvinVoigt ? "kelvin-voigt" : "hunt-crossley";
}

TissueParams tissue_preset(std::string_view name, ContactLaw law) {
  TissueParams t;
  t.name = std::string(name);
  t.law = law;
  t.lever_m = kLever;
  // Damping: Kelvin-Voigt c gives a damping ratio well below 1 against the
  // joint; Hunt-Crossley lambda ~ 0.2-1 s/m is typical of soft tissue.
  if (name == "none") {
    t.present = false;
  } else if (name == "soft") {
    t.present = true;
    t.outer_stiffness_n_per_m = kSoft;
    t.damping = law == ContactLaw::kKelvinVoigt ? 2.0 : 0.5;
  } else if (name == "hard") {
    t.present = true;
    t.outer_stiffness_n_per_m = kHard;
    t.damping = law == ContactLaw::kKelvinVoigt ? 6.0 : 0.3;
  } else if (name == "nodule") {
    t.present = true;
    t.outer_stiffness_n_per_m = kSoft;
    t.inclusion_depth_m = 0.15 * kLever;  // 0.15 rad of joint travel past the surface
    t.inclusion_stiffness_n_per_m = kHard;
    t.damping = law == ContactLaw::kKelvinVoigt ? 2.0 : 0.5;
  } else {
    throw std::invalid_argument("unknown tissue preset '" + std::string(name) +
                                "' (known: none, soft, hard, nodule)");
  }
  t.exponent = law == ContactLaw::kKelvinVoigt ? 1.0 : 1.5;
  return t;
}

void validate(const TissueParams& t) {
  const FieldChecks check("tissue '" + t.name + "':");
  check.require(std::isfinite(t.surface_rad), "surface_rad", "must be finite");
  check.positive(t.lever_m, "lever_m");
  check.non_negative(t.outer_stiffness_n_per_m, "outer_stiffness_n_per_m");
  check.require(!std::isnan(t.inclusion_depth_m) && t.inclusion_depth_m > 0, "inclusion_depth_m",
                "must be > 0 (infinity: no inclusion)");
  check.non_negative(t.inclusion_stiffness_n_per_m, "inclusion_stiffness_n_per_m");
  check.non_negative(t.damping, "damping");
  check.require(std::isfinite(t.exponent) && t.exponent >= 1.0 && t.exponent <= 3.0, "exponent",
                "must be in [1, 3]");
  check.positive(t.reference_depth_m, "reference_depth_m");
}

namespace {

double outer_force(const TissueParams& t, double d) {
  const double n = t.law == ContactLaw::kHuntCrossley ? t.exponent : 1.0;
  if (n == 1.0) return t.outer_stiffness_n_per_m * d;
  return t.outer_stiffness_n_per_m * t.reference_depth_m * std::pow(d / t.reference_depth_m, n);
}

double outer_slope(const TissueParams& t, double d) {
  const double n = t.law == ContactLaw::kHuntCrossley ? t.exponent : 1.0;
  if (n == 1.0) return t.outer_stiffness_n_per_m;
  return t.outer_stiffness_n_per_m * n * std::pow(d / t.reference_depth_m, n - 1.0);
}

}  // namespace

double elastic_force(const TissueParams& t, double d) {
  if (!t.present || d <= 0.0) return 0.0;
  if (d <= t.inclusion_depth_m) return outer_force(t, d);
  // Past the inclusion's top the force keeps growing with the inclusion's slope.
  return outer_force(t, t.inclusion_depth_m) +
         t.inclusion_stiffness_n_per_m * (d - t.inclusion_depth_m);
}

ContactState contact(const TissueParams& t, double q, double qd) {
  ContactState c;
  if (!t.present) return c;
  const double d = t.lever_m * (q - t.surface_rad);
  if (d <= 0.0) return c;
  const double dd = t.lever_m * qd;
  const double fe = elastic_force(t, d);
  const double f =
      t.law == ContactLaw::kKelvinVoigt ? fe + t.damping * dd : fe * (1.0 + t.damping * dd);
  c.indentation_m = d;
  c.force_n = std::max(0.0, f);  // tissue pushes, never pulls the tool
  c.torque_nm = t.lever_m * c.force_n;
  c.stiffness_n_per_m =
      d <= t.inclusion_depth_m ? outer_slope(t, d) : t.inclusion_stiffness_n_per_m;
  c.stiffness_nm_per_rad = c.stiffness_n_per_m * t.lever_m * t.lever_m;
  return c;
}

TissueTruth tissue_truth(const TissueParams& t) {
  TissueTruth truth;
  if (!t.present) return truth;
  const double l2 = t.lever_m * t.lever_m;
  truth.outer_n_per_m = t.outer_stiffness_n_per_m;
  truth.outer_nm_per_rad = t.outer_stiffness_n_per_m * l2;
  if (std::isfinite(t.inclusion_depth_m)) {
    truth.inclusion_n_per_m = t.inclusion_stiffness_n_per_m;
    truth.inclusion_nm_per_rad = t.inclusion_stiffness_n_per_m * l2;
    truth.inclusion_depth_m = t.inclusion_depth_m;
    truth.inclusion_depth_rad = t.inclusion_depth_m / t.lever_m;
  }
  return truth;
}

std::string tissue_description(const TissueParams& t) {
  if (!t.present) return "tissue " + t.name + ": none at the tool (free motion)";
  const TissueTruth truth = tissue_truth(t);
  char b[320];
  int n = std::snprintf(b, sizeof b,
                        "tissue %s: surface at joint angle %.3f rad, outer layer %.3f N m/rad",
                        t.name.c_str(), t.surface_rad, truth.outer_nm_per_rad);
  if (truth.inclusion_depth_rad > 0.0 && n > 0 && static_cast<std::size_t>(n) < sizeof b)
    std::snprintf(b + n, sizeof b - static_cast<std::size_t>(n),
                  ", inclusion (nodule) from joint angle %.3f rad (%.3f rad past the surface), "
                  "%.3f N m/rad",
                  t.surface_rad + truth.inclusion_depth_rad, truth.inclusion_depth_rad,
                  truth.inclusion_nm_per_rad);
  return b;
}

}  // namespace tsmh::virtual_tissue_slave
