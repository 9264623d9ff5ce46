#pragma once
// What the slave can measure: motor encoders, joint encoders, proximal load
// cells. Quantisation and noise are configurable; the noise generator is
// seeded so that offline runs are reproducible.

#include <cstdint>
#include <random>

#include "virtual_tissue_slave/joint_plant.hpp"

namespace tsmh::virtual_tissue_slave {

struct SensorParams {
  double motor_encoder_quantum_rad = 6.283185307179586 / 40960;  ///< 0: ideal
  double joint_encoder_quantum_rad = 6.283185307179586 / 65536;  ///< 0: ideal
  bool joint_encoder = true;         ///< false: x_out reads NaN (no joint encoder)
  double load_cell_noise_n = 0.02;   ///< standard deviation of white noise, N
  double load_cell_quantum_n = 0.0;  ///< 0: ideal
};

/// One joint's measurements at one instant.
struct Measurement {
  double x_in = 0.0;   ///< motor-side input pulley angle, rad
  double x_out = 0.0;  ///< joint angle, rad (NaN without a joint encoder)
  double T1 = 0.0;     ///< proximal tension, tendon 1, N
  double T3 = 0.0;     ///< proximal tension, tendon 2, N
};

/// Throws std::invalid_argument naming the bad field.
void validate(const SensorParams& sensors);

/// Rounds to the nearest multiple of `quantum` (no-op for quantum <= 0).
double quantize(double value, double quantum);

class Sensors {
 public:
  Sensors(const SensorParams& params, std::uint64_t seed);
  /// Does not allocate.
  Measurement measure(const JointTruth& truth);
  const SensorParams& params() const { return params_; }

 private:
  SensorParams params_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
};

}  // namespace tsmh::virtual_tissue_slave
