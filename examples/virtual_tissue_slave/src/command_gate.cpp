#include "virtual_tissue_slave/command_gate.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "field_checks.hpp"

namespace tsmh::virtual_tissue_slave {

void validate(const CommandGateParams& p) {
  const FieldChecks check("command gate");
  check.positive(p.timeout_s, "timeout_s");
  check.positive(p.max_velocity_rad_s, "max_velocity_rad_s");
  check.require(std::isfinite(p.min_rad) && std::isfinite(p.max_rad) && p.min_rad < p.max_rad,
                "min_rad", "must be finite and below max_rad");
}

CommandGate::CommandGate(const CommandGateParams& params,
                         const std::array<double, kJoints>& initial)
    : params_(params), reference_(initial) {
  validate(params);
  for (double& r : reference_)
    r = std::clamp(r, params_.min_rad, params_.max_rad);
}

const std::array<double, kJoints>& CommandGate::update(const CommandView& command, double dt) {
  const bool fresh = command.version != 0 && command.age_s <= params_.timeout_s;
  bool finite = true;
  for (double r : command.position_ref)
    finite = finite && std::isfinite(r);
  const bool follow = fresh && command.enable && !command.clutch && finite;
  status_ = follow ? kStatusEnabled : kStatusHolding;
  if (!follow) return reference_;  // hold: the reference stays where it is
  const double step = params_.max_velocity_rad_s * dt;
  for (std::size_t j = 0; j < kJoints; ++j) {
    const double target = std::clamp(command.position_ref[j], params_.min_rad, params_.max_rad);
    reference_[j] += std::clamp(target - reference_[j], -step, step);
  }
  return reference_;
}

}  // namespace tsmh::virtual_tissue_slave
