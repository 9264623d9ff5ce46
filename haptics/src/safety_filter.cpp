#include "haptics/safety_filter.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tsmh::haptics {

SafetyFilter::SafetyFilter(int joints, const std::array<JointSafetyLimits, kMaxJoints>& limits,
                           const SafetyTiming& timing)
    : joints_(joints), limits_(limits), timing_(timing) {
  if (joints < 1 || joints > static_cast<int>(kMaxJoints))
    throw std::invalid_argument("safety: joint count must be 1.." + std::to_string(kMaxJoints));
  for (int j = 0; j < joints; ++j) {
    const auto& l = limits_[static_cast<std::size_t>(j)];
    const std::string where = "joints[" + std::to_string(j) + "].";
    if (!(l.max_torque_nm > 0.0) || !std::isfinite(l.max_torque_nm))
      throw std::invalid_argument(where + "max_torque_nm: must be a finite number > 0");
    if (!(l.max_rate_nm_per_s > 0.0) || !std::isfinite(l.max_rate_nm_per_s))
      throw std::invalid_argument(where + "max_rate_nm_per_s: must be a finite number > 0");
  }
  if (!(timing_.stale_after_s > 0.0) || !std::isfinite(timing_.stale_after_s))
    throw std::invalid_argument("safety.stale_after_ms: must be > 0");
  if (!(timing_.fade_s > 0.0) || !std::isfinite(timing_.fade_s))
    throw std::invalid_argument("safety.fade_ms: must be > 0");
  if (!(timing_.recover_s > 0.0) || !std::isfinite(timing_.recover_s))
    throw std::invalid_argument("safety.recover_ms: must be > 0");
}

void SafetyFilter::reset() noexcept {
  gain_ = 0.0;
  out_ = {};
}

SafetyOutput SafetyFilter::apply(const JointArray& request, double dt_s, double source_age_s,
                                 bool enabled) noexcept {
  SafetyOutput out;
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) dt_s = 0.0;        // a bad clock step changes nothing
  const bool stale = !(source_age_s <= timing_.stale_after_s);  // NaN age counts as stale
  gain_ = stale ? std::max(0.0, gain_ - dt_s / timing_.fade_s)
                : std::min(1.0, gain_ + dt_s / timing_.recover_s);
  out.stale_gain = gain_;
  if (gain_ < 1.0) out.flags |= safety_flags::kStaleFade;
  if (!enabled) {
    out.flags |= safety_flags::kDisabled;
    out_ = out;  // torque zero at once
    return out_;
  }
  for (int j = 0; j < joints_; ++j) {
    const auto i = static_cast<std::size_t>(j);
    const auto& lim = limits_[i];
    double want = request[i];
    if (!std::isfinite(want)) {
      want = 0.0;
      out.flags |= safety_flags::kNonFinite;
    }
    want *= gain_;
    if (std::fabs(want) > lim.max_torque_nm) {
      want = std::copysign(lim.max_torque_nm, want);
      out.flags |= safety_flags::kSaturated;
    }
    const double step = lim.max_rate_nm_per_s * dt_s;
    const double prev = out_.torque[i];
    if (want > prev + step) {
      want = prev + step;
      out.flags |= safety_flags::kRateLimited;
    } else if (want < prev - step) {
      want = prev - step;
      out.flags |= safety_flags::kRateLimited;
    }
    out.torque[i] = want;
  }
  out_ = out;
  return out_;
}

}  // namespace tsmh::haptics
