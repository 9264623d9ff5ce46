#include "variants.hpp"

#include <limits>

namespace tsmh::accuracy {

namespace {
struct Variant {
  const char* name;
  void (*apply)(EstimatorVariant&);
};
constexpr double kNever = std::numeric_limits<double>::infinity();
const Variant kVariants[] = {
    {"deployed", [](EstimatorVariant&) {}},
    // The rest rule, in the causal sign and in hindsight.
    {"no-rest", [](EstimatorVariant& v) { v.corrections.still_time = 0.0; }},
    {"no-cruise", [](EstimatorVariant& v) { v.corrections.cruise_window = 0.0; }},
    {"no-hindsight", [](EstimatorVariant& v) { v.corrections.hindsight.lag = 0.0; }},
    // Hindsight from the fine channel only (its rest part stays).
    {"no-fine-hindsight",
     [](EstimatorVariant& v) {
       v.corrections.hindsight.sure = v.corrections.hindsight.sure_armed = kNever;
     }},
};
}  // namespace

std::vector<std::string> variant_names() {
  std::vector<std::string> out;
  for (const auto& v : kVariants)
    out.emplace_back(v.name);
  return out;
}

std::optional<EstimatorVariant> estimator_variant(const std::string& name) {
  for (const auto& v : kVariants) {
    if (name != v.name) continue;
    EstimatorVariant e;
    v.apply(e);
    return e;
  }
  return std::nullopt;
}

}  // namespace tsmh::accuracy
