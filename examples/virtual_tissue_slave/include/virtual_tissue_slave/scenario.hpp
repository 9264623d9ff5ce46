#pragma once
// Offline scenarios: joint references as functions of time, and the tissue
// each one is meant to be run against.

#include <string>
#include <string_view>
#include <vector>

namespace tsmh::virtual_tissue_slave {

enum class ScenarioKind { kSine, kMultisine, kPalpate, kChirp, kExcite, kIdentify };

struct Scenario {
  ScenarioKind kind = ScenarioKind::kSine;
  std::string name;
  std::string description;
  double default_duration_s = 30.0;
  std::string tissue = "none";  ///< default tissue preset, both joints
  double surface_rad = 0.6;     ///< default tissue surface angle, rad

  /// Joint reference at time t (s) for joint index 0 (Joint1) or 1 (Joint2), rad.
  double reference(double t, int joint) const;
};

std::vector<std::string> scenario_names();
/// Throws std::invalid_argument naming the unknown scenario and the known ones.
Scenario make_scenario(std::string_view name);

}  // namespace tsmh::virtual_tissue_slave
