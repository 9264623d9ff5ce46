#include "estimator/parameter_map.hpp"

#include <algorithm>
#include <cmath>

namespace tsmh::estimator {

ParameterMap::ParameterMap(const std::vector<Parameter>& params,
                           const std::vector<BoundsOverride>& overrides) {
  for (std::size_t i = 0; i < params.size(); ++i) {
    Parameter p = params[i];
    for (const auto& o : overrides) {
      if (o.name == p.name) {
        p.lower = std::max(o.lower, params[i].lower);
        p.upper = std::min(o.upper, params[i].upper);
      }
    }
    template_.push_back(p.value);
    if (p.fixed || !(p.upper > p.lower)) continue;
    FreeParameter f;
    f.index = i;
    f.name = p.name;
    f.lower = p.lower;
    f.upper = p.upper;
    if (p.lower > 0.0 && p.upper / p.lower >= 20.0) {
      f.scale = ParameterScale::kLog;
    } else if (p.lower == 0.0 && p.upper > 0.0) {
      f.scale = ParameterScale::kLogOffset;
      f.offset = p.upper / 1000.0;
    }
    free_.push_back(f);
  }
}

double ParameterMap::to_unit(std::size_t k, double value) const {
  const auto& f = free_[k];
  const double v = std::clamp(value, f.lower, f.upper);
  switch (f.scale) {
    case ParameterScale::kLog:
      return std::log(v / f.lower) / std::log(f.upper / f.lower);
    case ParameterScale::kLogOffset:
      return std::log((v + f.offset) / (f.lower + f.offset)) /
             std::log((f.upper + f.offset) / (f.lower + f.offset));
    case ParameterScale::kLinear:
      break;
  }
  return (v - f.lower) / (f.upper - f.lower);
}

double ParameterMap::from_unit(std::size_t k, double u) const {
  const auto& f = free_[k];
  const double c = std::clamp(u, 0.0, 1.0);
  double v = 0.0;
  switch (f.scale) {
    case ParameterScale::kLog:
      v = f.lower * std::pow(f.upper / f.lower, c);
      break;
    case ParameterScale::kLogOffset:
      v = (f.lower + f.offset) * std::pow((f.upper + f.offset) / (f.lower + f.offset), c) -
          f.offset;
      break;
    case ParameterScale::kLinear:
      v = f.lower + c * (f.upper - f.lower);
      break;
  }
  return std::clamp(v, f.lower, f.upper);
}

std::vector<double> ParameterMap::to_unit(std::span<const double> values) const {
  std::vector<double> u(free_.size());
  for (std::size_t k = 0; k < free_.size(); ++k)
    u[k] = to_unit(k, values[free_[k].index]);
  return u;
}

void ParameterMap::to_values(std::span<const double> u, std::vector<double>& out) const {
  if (out.size() != template_.size()) out = template_;
  for (std::size_t k = 0; k < free_.size(); ++k)
    out[free_[k].index] = from_unit(k, u[k]);
}

}  // namespace tsmh::estimator
