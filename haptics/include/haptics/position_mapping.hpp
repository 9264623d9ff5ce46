#pragma once
// Master joint angle -> slave joint position reference, with clutching
// (indexing): while the clutch is held the reference freezes and the master
// may move freely; on release the offset is re-based so the reference
// continues from where it froze, without a jump.

#include <algorithm>
#include <cmath>

namespace tsmh::haptics {

struct PositionMappingConfig {
  double scale = 1.0;     ///< slave rad per master rad
  double sign = 1.0;      ///< +1 or -1
  double offset = 0.0;    ///< slave rad at master 0 (initial)
  double min_ref = -1e9;  ///< slave workspace, rad
  double max_ref = 1e9;
};

class PositionMapping {
 public:
  PositionMapping() = default;
  explicit PositionMapping(const PositionMappingConfig& c) : c_(c), offset_(c.offset) {}

  /// Reference for master angle q. Non-finite q holds the last reference.
  double update(double q, bool clutch) noexcept {
    if (!std::isfinite(q)) return ref_;
    if (clutch) {
      clutched_ = true;
      return ref_;
    }
    if (clutched_) {
      offset_ = ref_ - c_.sign * c_.scale * q;  // re-index: continue from the frozen reference
      clutched_ = false;
    }
    ref_ = std::clamp(offset_ + c_.sign * c_.scale * q, c_.min_ref, c_.max_ref);
    return ref_;
  }

  /// Re-bases so that the current master angle maps to `slave_ref` (used when
  /// enabling, so the slave does not jump to the master's position).
  void align(double q, double slave_ref) noexcept {
    if (!std::isfinite(q) || !std::isfinite(slave_ref)) return;
    offset_ = slave_ref - c_.sign * c_.scale * q;
    ref_ = std::clamp(slave_ref, c_.min_ref, c_.max_ref);
    clutched_ = false;
  }

  double reference() const noexcept { return ref_; }
  const PositionMappingConfig& config() const noexcept { return c_; }

 private:
  PositionMappingConfig c_{};
  double offset_ = 0.0;
  double ref_ = 0.0;
  bool clutched_ = false;
};

}  // namespace tsmh::haptics
