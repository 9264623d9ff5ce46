#pragma once
// Parsing of the command-line forms of hidden effects and per-sheath pairs,
// with errors that name the option and the bad part.

#include <string>
#include <utility>
#include <vector>

#include "virtual_tissue_slave/joint_plant.hpp"

namespace tsmh::virtual_tissue_slave {

/// Known effect names, for help texts and errors.
std::string effect_names();

/// Applies "NAME=VALUE" specs in order to `base`:
///   viscous=C     extra sheath drag, N of total friction per rad/s (>= 0)
///   capstan=0|1   0: friction no longer grows with the transmitted load
///   position=G    wraps scale by (1 + G x_in): friction depends on position
/// Throws std::invalid_argument naming the spec at fault.
FrictionEffects parse_effects(const std::vector<std::string>& specs, FrictionEffects base = {});

/// "A,B" -> {A, B}; "A" -> {A, NaN}. `option` names the flag in errors.
/// Values must be finite numbers.
std::pair<double, double> parse_pair(const std::string& text, const std::string& option);

}  // namespace tsmh::virtual_tissue_slave
