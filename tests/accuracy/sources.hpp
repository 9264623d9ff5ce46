#pragma once
// The recordings the accuracy judge scores on, with their truth: the
// independent physics world, the paper's own model (the estimator's
// synthetic generator) and the virtual slave run offline. Each "set" is one
// seed: a calibration recording that the models are fitted on and test
// recordings of the same plant (other motions, other noise) that the
// deployed estimator runs on.

#include <cstdint>
#include <string>
#include <vector>

#include "estimator/recording.hpp"

namespace tsmh::accuracy {

struct Scored {
  std::string kind;                   ///< the motion kind or scenario
  estimator::Recording rec;           ///< what the sensors saw (no exact derivatives)
  std::vector<double> friction_true;  ///< N, (tau_in - tau_out)/R without noise
  std::vector<double> tau_out_true;   ///< N m, the true tip torque
  std::vector<char> contact;          ///< 1 in contact; empty where the source has no contact
};

struct Set {
  std::string source;  ///< "world", "paper" or "slave"
  std::uint64_t seed = 0;
  Scored calibration;
  std::vector<Scored> tests;
};

/// The kinds each source has, and its default test kinds.
std::vector<std::string> source_kinds(const std::string& source);

/// Throws std::invalid_argument for an unknown source or kind.
Set make_set(const std::string& source, std::uint64_t seed, const std::vector<std::string>& kinds,
             double duration_s);

}  // namespace tsmh::accuracy
