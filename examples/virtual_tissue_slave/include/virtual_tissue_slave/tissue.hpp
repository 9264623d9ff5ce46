#pragma once
// Tissue at the tool: a one-sided contact (it pushes, never pulls) between the
// tool tip and a tissue surface. The tool tip sits `lever_m` from the joint
// axis, so a joint angle q past the surface angle q_s indents the tissue by
// delta = lever_m * (q - q_s). The elastic force has the outer layer's slope
// until the tool reaches an inclusion `inclusion_depth_m` deep, then the
// inclusion's slope: the `nodule` preset is soft tissue over a hard lump.

#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace tsmh::virtual_tissue_slave {

enum class ContactLaw {
  kKelvinVoigt,   ///< F = Fe(delta) + c * delta_dot, clamped at >= 0
  kHuntCrossley,  ///< F = Fe(delta) * (1 + lambda * delta_dot), >= 0: no force jump at impact
};

struct TissueParams {
  std::string name = "none";
  bool present = false;  ///< false: free motion, no contact anywhere
  ContactLaw law = ContactLaw::kKelvinVoigt;
  double surface_rad = 0.3;              ///< joint angle at which the tool touches the surface, rad
  double lever_m = 0.03;                 ///< joint axis to tool tip, m
  double outer_stiffness_n_per_m = 0.0;  ///< slope of the outer layer, N/m
  double inclusion_depth_m =
      std::numeric_limits<double>::infinity();  ///< depth of a hard inclusion, m
  double inclusion_stiffness_n_per_m = 0.0;     ///< slope once the inclusion is reached, N/m
  double damping = 0.0;  ///< Kelvin-Voigt c (N s/m) or Hunt-Crossley lambda (s/m)
  /// Hunt-Crossley exponent n of the outer layer: Fe = k * d_ref * (delta/d_ref)^n,
  /// so k stays the secant stiffness at d_ref. Kelvin-Voigt always uses 1.
  double exponent = 1.0;
  double reference_depth_m = 0.002;  ///< d_ref above, m
};

/// Contact state at one instant.
struct ContactState {
  double indentation_m = 0.0;         ///< delta, m (0 when not in contact)
  double force_n = 0.0;               ///< contact force on the tool, N (>= 0)
  double torque_nm = 0.0;             ///< joint torque opposing the indentation, N m (>= 0)
  double stiffness_n_per_m = 0.0;     ///< local elastic slope dFe/d(delta), N/m
  double stiffness_nm_per_rad = 0.0;  ///< the same in joint space, N m/rad
};

/// The stiffness values a demo reports as the truth beside the perceived ones.
struct TissueTruth {
  double outer_n_per_m = 0.0;
  double outer_nm_per_rad = 0.0;
  double inclusion_n_per_m = 0.0;  ///< 0 when there is no inclusion
  double inclusion_nm_per_rad = 0.0;
  double inclusion_depth_m = 0.0;    ///< 0 when there is no inclusion
  double inclusion_depth_rad = 0.0;  ///< joint travel past the surface to reach it
};

/// Names of the presets: "none", "soft", "hard", "nodule".
std::vector<std::string> tissue_preset_names();
/// A preset with the given contact law. Throws std::invalid_argument naming the
/// unknown preset and listing the known ones.
TissueParams tissue_preset(std::string_view name, ContactLaw law = ContactLaw::kKelvinVoigt);
/// "kelvin-voigt" or "hunt-crossley"; throws std::invalid_argument otherwise.
ContactLaw parse_contact_law(std::string_view name);
std::string_view contact_law_name(ContactLaw law);

/// Throws std::invalid_argument naming the bad field.
void validate(const TissueParams& tissue);
TissueTruth tissue_truth(const TissueParams& tissue);
/// One line for logs: what the angles and slopes are ("tissue nodule: surface
/// at joint angle 0.200 rad, ..."), so a bare "0.200 rad" is never read as
/// the nodule's place.
std::string tissue_description(const TissueParams& tissue);

/// Elastic force at indentation delta (>= 0), N.
double elastic_force(const TissueParams& tissue, double delta_m);
/// Contact at joint angle q (rad) and velocity qd (rad/s).
ContactState contact(const TissueParams& tissue, double q_rad, double qd_rad_s);

}  // namespace tsmh::virtual_tissue_slave
