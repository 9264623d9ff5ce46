#pragma once
// Estimator variants the judge can score beside the deployed one: the
// deployed CorrectionsConfig with one correction switched off, so that
// what each correction does is measured on data it was not tuned to (the
// independent physics world, the virtual slave, held-out paper-model sets).
// These switches exist for this measurement only; haptic-server deploys
// DifferentiatorConfig{} and CorrectionsConfig{}.

#include <optional>
#include <string>
#include <vector>

#include "estimator/corrections.hpp"
#include "estimator/differentiator.hpp"

namespace tsmh::accuracy {

/// The variant names --variants accepts.
std::vector<std::string> variant_names();

/// The estimator's settings a variant changes.
struct EstimatorVariant {
  estimator::DifferentiatorConfig diff;
  estimator::CorrectionsConfig corrections;
};

/// The deployed settings with `name`'s change, nullopt for an unknown name.
std::optional<EstimatorVariant> estimator_variant(const std::string& name);

}  // namespace tsmh::accuracy
