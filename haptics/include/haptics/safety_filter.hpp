#pragma once
// The last stage before the device: whatever the torque request (NaN, Inf,
// huge, stale), what leaves here is finite, within the configured limit and
// rate, and fades to zero when its source dies. Pure value type: no clock,
// no device, no threads, so every rule is testable in simulated time.
//
// Rules, in order:
//  1. A non-finite request for a joint becomes 0 for that joint (flagged).
//  2. The stale gain g in [0, 1] falls linearly to 0 over `fade` once the
//     source is older than `stale_after`, and rises back to 1 over `recover`
//     once it is fresh again: force fades out and returns smoothly.
//  3. g * request is clamped to +-max_torque.
//  4. The change per tick is limited to max_rate * dt (no steps felt as a
//     kick) -- except that disabling (dead-man, e-stop, fault) zeroes the
//     output at once: removing torque is always safe.

#include <cstdint>

#include "haptics/joint_array.hpp"

namespace tsmh::haptics {

struct JointSafetyLimits {
  double max_torque_nm = 0.0;      ///< |torque| never exceeds this
  double max_rate_nm_per_s = 0.0;  ///< |d torque / dt| never exceeds this (while enabled)
};

struct SafetyTiming {
  double stale_after_s = 0.020;  ///< source older than this: fade out
  double fade_s = 0.050;         ///< full torque to zero
  double recover_s = 0.200;      ///< zero back to full torque
};

namespace safety_flags {
inline constexpr std::uint32_t kStaleFade = 1u << 0;  ///< stale gain < 1
inline constexpr std::uint32_t kSaturated = 1u << 3;
inline constexpr std::uint32_t kRateLimited = 1u << 4;
inline constexpr std::uint32_t kNonFinite = 1u << 5;
inline constexpr std::uint32_t kDisabled = 1u << 6;
}  // namespace safety_flags

struct SafetyOutput {
  JointArray torque{};      ///< what may go to the device, N m
  double stale_gain = 0.0;  ///< 0..1
  std::uint32_t flags = 0;  ///< safety_flags bits
};

class SafetyFilter {
 public:
  /// Throws std::invalid_argument naming the bad value (limits must be finite
  /// and > 0, timings > 0).
  SafetyFilter(int joints, const std::array<JointSafetyLimits, kMaxJoints>& limits,
               const SafetyTiming& timing);

  /// One tick. `dt_s` since the previous tick, `source_age_s` of the newest
  /// input (use +inf when there has never been one), `enabled` whether torque
  /// may be rendered at all. Never allocates or throws.
  SafetyOutput apply(const JointArray& request, double dt_s, double source_age_s,
                     bool enabled) noexcept;

  void reset() noexcept;
  const SafetyOutput& last() const noexcept { return out_; }
  int joints() const noexcept { return joints_; }

 private:
  int joints_;
  std::array<JointSafetyLimits, kMaxJoints> limits_;
  SafetyTiming timing_;
  double gain_ = 0.0;
  SafetyOutput out_;
};

}  // namespace tsmh::haptics
