#include "bridge/validation.hpp"

#include <cmath>
#include <cstdio>

namespace tsmh::bridge {
namespace {

// Checks the first n entries of one joint array. `allow_nan`: NaN means
// "not measured" for this field (x_out of a joint without encoder).
std::optional<Rejection> check(const char* name, const JointArray& a, int n, const Range& range,
                               bool allow_nan = false) noexcept {
  for (int j = 0; j < n; ++j) {
    const double v = a[static_cast<std::size_t>(j)];
    if (std::isnan(v) && allow_nan) continue;
    if (!std::isfinite(v)) return make_rejection(RejectReason::kNonFinite, name, v, j);
    if (!range.contains(v)) return make_rejection(RejectReason::kOutOfRange, name, v, j);
  }
  return std::nullopt;
}

// |next - prev| <= max_step for the first n joints; NaN on either side (an
// absent encoder) is not a step. max_step <= 0 disables the check.
std::optional<Rejection> check_step(const char* name, const JointArray& prev,
                                    const JointArray& next, int n, double max_step) noexcept {
  if (!(max_step > 0.0)) return std::nullopt;
  for (int j = 0; j < n; ++j) {
    const auto k = static_cast<std::size_t>(j);
    const double d = next[k] - prev[k];
    if (std::fabs(d) > max_step) return make_rejection(RejectReason::kImplausible, name, d, j);
  }
  return std::nullopt;
}

}  // namespace

std::optional<Rejection> check_step(const SlaveStateSample& prev, const SlaveStateSample& next,
                                    double elapsed_s, const SlaveStateLimits& l) noexcept {
  const double t = (elapsed_s > 0.0 ? elapsed_s : 0.0) + l.step_slack_s;
  const int n = next.num_joints < prev.num_joints ? next.num_joints : prev.num_joints;
  if (auto r = check_step("x_in", prev.x_in, next.x_in, n, l.max_x_in_rate_rad_s * t)) return r;
  if (auto r = check_step("x_out", prev.x_out, next.x_out, n, l.max_x_out_rate_rad_s * t)) return r;
  if (auto r = check_step("T1", prev.T1, next.T1, n, l.max_tension_rate_n_per_s * t)) return r;
  return check_step("T3", prev.T3, next.T3, n, l.max_tension_rate_n_per_s * t);
}

std::optional<Rejection> check_joint_count(int num_joints, int expected) noexcept {
  if (num_joints < 1 || num_joints > static_cast<int>(kMaxJoints)) {
    char what[96];
    std::snprintf(what, sizeof what, "num_joints must be 1..%zu", kMaxJoints);
    return make_rejection(RejectReason::kJointCount, what, num_joints);
  }
  if (expected > 0 && num_joints != expected) {
    char what[96];
    std::snprintf(what, sizeof what, "configured for %d joints", expected);
    return make_rejection(RejectReason::kJointCount, what, num_joints);
  }
  return std::nullopt;
}

std::optional<Rejection> validate(const SlaveStateSample& s, const SlaveStateLimits& l) noexcept {
  const int n = s.num_joints;
  if (auto r = check("x_in", s.x_in, n, l.x_in)) return r;
  if (auto r = check("x_out", s.x_out, n, l.x_out, /*allow_nan=*/true)) return r;
  if (auto r = check("T1", s.T1, n, l.tension)) return r;
  if (auto r = check("T3", s.T3, n, l.tension)) return r;
  return check("radius_m", s.radius_m, n, l.radius_m);
}

std::optional<Rejection> validate(const SlaveTruthSample& s, const SlaveTruthLimits& l) noexcept {
  const int n = s.num_joints;
  if (auto r = check("tau_out", s.tau_out, n, l.tau_out)) return r;
  if (auto r = check("friction", s.friction, n, l.friction)) return r;
  if (auto r = check("tau_in", s.tau_in, n, l.tau_in)) return r;
  if (auto r = check("x_out", s.x_out, n, l.x_out)) return r;
  if (auto r = check("contact_force", s.contact_force, n, l.contact_force)) return r;
  return check("indentation", s.indentation, n, l.indentation);
}

std::optional<Rejection> validate(const MasterCommandSample& s,
                                  const MasterCommandLimits& l) noexcept {
  return check("position_ref", s.position_ref, s.num_joints, l.position_ref);
}

std::optional<Rejection> validate(const HapticStatusSample& /*s*/,
                                  const HapticStatusLimits& /*l*/) noexcept {
  return std::nullopt;
}

std::optional<Rejection> validate(const CalibrationRequestSample& /*s*/,
                                  const CalibrationRequestLimits& /*l*/) noexcept {
  return std::nullopt;
}

}  // namespace tsmh::bridge
