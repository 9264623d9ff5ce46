#pragma once
// The optimiser's view of a model's parameters: only the free ones (not
// Parameter::fixed), each mapped to u in [0, 1] over its bounds. Positive
// parameters spanning decades (theta 0.1..1000, rho 0.01..20) are mapped on a
// log scale, and those whose lower bound is 0 (kappa, mu) on a log scale of
// (value + offset), offset = upper / 1000, so a search step means the same
// relative change near 0.01 as near 10. Everything else is linear.

#include <span>
#include <string>
#include <vector>

#include "estimator/friction_model.hpp"

namespace tsmh::estimator {

enum class ParameterScale { kLinear, kLog, kLogOffset };

struct FreeParameter {
  std::size_t index = 0;  ///< position in FrictionModel::parameters()
  std::string name;
  double lower = 0.0;
  double upper = 0.0;
  ParameterScale scale = ParameterScale::kLinear;
  double offset = 0.0;  ///< for log_offset
};

/// Narrower search bounds for one parameter than the model declares (e.g. a
/// step time within the recording).
struct BoundsOverride {
  std::string name;
  double lower = 0.0;
  double upper = 0.0;
};

class ParameterMap {
 public:
  /// From the model's parameters (values become the template for fixed ones);
  /// `overrides` replace the bounds of the named parameters.
  explicit ParameterMap(const std::vector<Parameter>& params,
                        const std::vector<BoundsOverride>& overrides = {});

  std::size_t size() const { return free_.size(); }
  const std::vector<FreeParameter>& free() const { return free_; }
  /// All parameter values of the template (fixed ones included).
  const std::vector<double>& template_values() const { return template_; }

  /// u in [0, 1] for a free parameter's value (clamped to its bounds).
  double to_unit(std::size_t k, double value) const;
  double from_unit(std::size_t k, double u) const;

  /// u for the free parameters of a full value vector.
  std::vector<double> to_unit(std::span<const double> values) const;
  /// Full value vector (fixed ones from the template) for u. `out` is resized
  /// once; no allocation when it already has the right size.
  void to_values(std::span<const double> u, std::vector<double>& out) const;

 private:
  std::vector<FreeParameter> free_;
  std::vector<double> template_;
};

}  // namespace tsmh::estimator
