#pragma once
// Friction model parameter files (YAML, docs/data-formats.md) and the
// built-in presets. A file holds the model family, its terms and values:
//
//   model: tsm
//   core: {theta: 15.5181, gamma: 9.5651, n: 2, sigma: 1}
//   terms:
//     coulomb: {rho1: 1.038}
//     stribeck: {mu1: 1.0978, kappa1: 6.1264}
//   fixed: [core.gamma, core.n]
//
// Reading validates every field and names the bad one, e.g.
// "params.yaml: terms.stribeck.kappa1: must be a number".

#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "estimator/friction_model.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {

/// A parameter file that cannot be used. The message names file and field.
class ParamsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Names accepted by load_model besides a file path.
std::vector<std::string> preset_names();  // paper, dahl, dahl_classic, lugre, coulomb_capstan

/// A preset name or a YAML file. Throws ParamsError.
std::unique_ptr<FrictionModel> load_model(const std::string& preset_or_path);
/// Parses YAML text (`origin` names it in errors). Throws ParamsError.
std::unique_ptr<FrictionModel> parse_model(const std::string& yaml_text, const std::string& origin);

/// YAML text for a model; `header` lines become comments at the top.
std::string model_to_yaml(const FrictionModel& model, const std::vector<std::string>& header = {});
/// Writes model_to_yaml atomically (temporary file renamed into place).
void save_model(const FrictionModel& model, const std::filesystem::path& path,
                const std::vector<std::string>& header = {});

}  // namespace tsmh::estimator
