#pragma once
// The whole virtual slave: two joints (Joint1 the gripper, Joint2), their
// sensors and controllers, advanced one control period at a time.

#include <array>
#include <cstdint>

#include "virtual_tissue_slave/controller.hpp"
#include "virtual_tissue_slave/joint_plant.hpp"
#include "virtual_tissue_slave/sensors.hpp"

namespace tsmh::virtual_tissue_slave {

inline constexpr int kJoints = 2;

struct SlaveParams {
  std::array<JointParams, kJoints> joints;
  std::array<ControllerParams, kJoints> controllers;
  SensorParams sensors;
  double control_period_s = 0.001;  ///< controller and sensor rate (1 kHz)
  int substeps = 10;                ///< physics steps per control period
};

/// The paper-scale slave (docs/virtual-slave.md): R = 0.01 m, 1.5 m sheaths, a total
/// friction loop of about +10 N / -9 N on Joint1 for a 0.8 rad 0.5 Hz sine,
/// backlash of about 0.2 rad, sheaths of unequal wrap and pretension.
SlaveParams paper_slave();
/// Throws std::invalid_argument naming the bad field.
void validate(const SlaveParams& params);

struct SlaveSample {
  double t = 0.0;  ///< s since start (or since the end of settle())
  std::array<Measurement, kJoints> measured;
  std::array<JointTruth, kJoints> truth;
  std::array<double, kJoints> reference{};        ///< joint reference used, rad
  std::array<double, kJoints> motor_reference{};  ///< controller's motor reference, rad
};

class VirtualSlave {
 public:
  VirtualSlave(const SlaveParams& params, std::uint64_t seed);

  /// Measures the joints at the current time, runs the controllers towards
  /// `references` and advances the physics by one control period. Returns the
  /// sample taken at the start of the period. Does not allocate.
  const SlaveSample& tick(const std::array<double, kJoints>& references);
  /// Holds `references` for `seconds` (the pretension settles), then restarts
  /// the clock at 0.
  void settle(const std::array<double, kJoints>& references, double seconds);

  double time() const { return time_; }
  JointPlant& joint(int index) { return plants_[static_cast<std::size_t>(index)]; }
  const JointPlant& joint(int index) const { return plants_[static_cast<std::size_t>(index)]; }
  const JointController& controller(int index) const {
    return controllers_[static_cast<std::size_t>(index)];
  }
  const SlaveParams& params() const { return params_; }
  /// The most recent sample (valid after the first tick).
  const SlaveSample& last() const { return sample_; }

 private:
  SlaveParams params_;
  std::array<JointPlant, kJoints> plants_;
  std::array<JointController, kJoints> controllers_;
  std::array<Sensors, kJoints> sensors_;
  SlaveSample sample_;
  double time_ = 0.0;
  long ticks_ = 0;
};

}  // namespace tsmh::virtual_tissue_slave
