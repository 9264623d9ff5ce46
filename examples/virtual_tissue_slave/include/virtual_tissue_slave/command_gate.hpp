#pragma once
// Turns the stream of MASTER_COMMANDs into the joint references the
// controllers track, safely: a stale, disabled or clutched command freezes
// the reference where it is (the slave holds position); references are
// clamped to the joint range and rate limited, so neither a jump in the
// command nor the return of commands after a gap makes the joint leap.

#include <array>
#include <cstdint>

#include "virtual_tissue_slave/slave.hpp"

namespace tsmh::virtual_tissue_slave {

struct CommandGateParams {
  double timeout_s = 0.1;           ///< no new command for this long: hold
  double max_velocity_rad_s = 6.0;  ///< reference rate limit
  double min_rad = -1.4;            ///< joint range
  double max_rad = 1.4;
};

/// Throws std::invalid_argument naming the bad field.
void validate(const CommandGateParams& params);

/// The newest command as the node sees it.
struct CommandView {
  std::uint64_t version = 0;  ///< 0: no command has ever arrived
  double age_s = 0.0;         ///< since it was received
  bool enable = false;
  bool clutch = false;
  std::array<double, kJoints> position_ref{};
};

/// SLAVE_STATE status bits.
enum StatusBits : std::int32_t {
  kStatusEnabled = 1 << 0,  ///< following fresh, enabled commands
  kStatusHolding = 1 << 1,  ///< holding position (no fresh command, disabled or clutched)
  kStatusFault = 1 << 2,
};

class CommandGate {
 public:
  /// `initial` is the reference held until the first usable command.
  CommandGate(const CommandGateParams& params, const std::array<double, kJoints>& initial);
  /// One control period of dt seconds. Does not allocate.
  const std::array<double, kJoints>& update(const CommandView& command, double dt);
  const std::array<double, kJoints>& reference() const { return reference_; }
  std::int32_t status() const { return status_; }

 private:
  CommandGateParams params_;
  std::array<double, kJoints> reference_;
  std::int32_t status_ = kStatusHolding;
};

}  // namespace tsmh::virtual_tissue_slave
