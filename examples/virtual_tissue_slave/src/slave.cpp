#include "virtual_tissue_slave/slave.hpp"

#include <cmath>
#include <stdexcept>

namespace tsmh::virtual_tissue_slave {

namespace {

struct Sheath {
  double wrap_rad;
  double pretension_n;
};

JointParams& set_joint(JointParams& j, const char* name, Sheath sheath01, Sheath sheath02) {
  j.name = name;
  j.tendon1.wrap_rad = sheath01.wrap_rad;
  j.tendon1.pretension_n = sheath01.pretension_n;
  j.tendon2.wrap_rad = sheath02.wrap_rad;
  j.tendon2.pretension_n = sheath02.pretension_n;
  return j;
}

}  // namespace

SlaveParams paper_slave() {
  SlaveParams p;
  // Joint1, the gripper. Sheath 01 is wound more than sheath 02 (they follow
  // different sides of the endoscope's tool channel), so the friction loop is
  // asymmetric: the puller's capstan gain e^(mu Theta) differs per direction.
  set_joint(p.joints[0], "joint1", {3.4, 21.0}, {1.2, 20.0});
  // Joint2: the other way round, a slightly heavier link.
  JointParams& j2 = set_joint(p.joints[1], "joint2", {1.6, 20.0}, {3.0, 22.0});
  j2.output_inertia = 8e-6;
  j2.output_damping = 6e-3;
  return p;
}

void validate(const SlaveParams& p) {
  if (!(std::isfinite(p.control_period_s) && p.control_period_s > 0 && p.control_period_s <= 0.1))
    throw std::invalid_argument("slave field 'control_period_s' must be in (0, 0.1]");
  if (p.substeps < 1 || p.substeps > 1000)
    throw std::invalid_argument("slave field 'substeps' must be in [1, 1000]");
  for (const auto& c : p.controllers)
    validate(c);
  validate(p.sensors);
}

namespace {
const SlaveParams& validated(const SlaveParams& p) {
  validate(p);
  return p;
}
}  // namespace

VirtualSlave::VirtualSlave(const SlaveParams& params, std::uint64_t seed)
    : params_(validated(params)),
      plants_{JointPlant(params.joints[0]), JointPlant(params.joints[1])},
      controllers_{JointController(params.controllers[0]), JointController(params.controllers[1])},
      // Distinct, reproducible noise streams per joint.
      sensors_{Sensors(params.sensors, seed * 2 + 1), Sensors(params.sensors, seed * 2 + 2)} {}

const SlaveSample& VirtualSlave::tick(const std::array<double, kJoints>& references) {
  const double dt = params_.control_period_s;
  const double h = dt / params_.substeps;
  sample_.t = time_;
  for (std::size_t j = 0; j < kJoints; ++j) {
    JointPlant& plant = plants_[j];
    sample_.truth[j] = plant.truth();
    sample_.measured[j] = sensors_[j].measure(plant.truth());
    sample_.reference[j] = references[j];
    const double torque =
        controllers_[j].update(references[j], sample_.measured[j], plant.params().radius_m, dt);
    sample_.motor_reference[j] = controllers_[j].motor_reference();
    for (int s = 0; s < params_.substeps; ++s)
      plant.step(torque, h);
  }
  ++ticks_;
  time_ = static_cast<double>(ticks_) * dt;  // no drift from repeated addition
  return sample_;
}

void VirtualSlave::settle(const std::array<double, kJoints>& references, double seconds) {
  const long n = std::lround(seconds / params_.control_period_s);
  for (long i = 0; i < n; ++i)
    tick(references);
  ticks_ = 0;
  time_ = 0.0;
}

}  // namespace tsmh::virtual_tissue_slave
