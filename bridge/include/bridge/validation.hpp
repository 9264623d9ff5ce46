#pragma once
// Content checks of decoded samples against the configured limits. Pure
// functions: the first problem found is returned, nothing is allocated.

#include <optional>

#include "bridge/limits.hpp"
#include "bridge/rejection.hpp"
#include "bridge/samples.hpp"

namespace tsmh::bridge {

/// num_joints must be in 1..kMaxJoints and, when `expected` > 0, equal it.
std::optional<Rejection> check_joint_count(int num_joints, int expected) noexcept;

std::optional<Rejection> validate(const SlaveStateSample& s, const SlaveStateLimits& l) noexcept;
std::optional<Rejection> validate(const SlaveTruthSample& s, const SlaveTruthLimits& l) noexcept;
std::optional<Rejection> validate(const MasterCommandSample& s,
                                  const MasterCommandLimits& l) noexcept;
std::optional<Rejection> validate(const HapticStatusSample& s,
                                  const HapticStatusLimits& l) noexcept;
std::optional<Rejection> validate(const CalibrationRequestSample& s,
                                  const CalibrationRequestLimits& l) noexcept;

/// Whether `next` can follow `prev` (the last accepted sample) physically:
/// SLAVE_STATE angles and tensions must not step faster than the limits'
/// rates over `elapsed_s` (+ step_slack_s). Other types have no such bound.
std::optional<Rejection> check_step(const SlaveStateSample& prev, const SlaveStateSample& next,
                                    double elapsed_s, const SlaveStateLimits& l) noexcept;
template <class Sample, class Limits>
std::optional<Rejection> check_step(const Sample& /*prev*/, const Sample& /*next*/,
                                    double /*elapsed_s*/, const Limits& /*l*/) noexcept {
  return std::nullopt;
}

}  // namespace tsmh::bridge
