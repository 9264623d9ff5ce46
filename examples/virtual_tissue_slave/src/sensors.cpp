#include "virtual_tissue_slave/sensors.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace tsmh::virtual_tissue_slave {

void validate(const SensorParams& s) {
  auto require = [](bool ok, const char* field) {
    if (!ok) throw std::invalid_argument(std::string("sensor field '") + field + "' must be >= 0");
  };
  require(std::isfinite(s.motor_encoder_quantum_rad) && s.motor_encoder_quantum_rad >= 0,
          "motor_encoder_quantum_rad");
  require(std::isfinite(s.joint_encoder_quantum_rad) && s.joint_encoder_quantum_rad >= 0,
          "joint_encoder_quantum_rad");
  require(std::isfinite(s.load_cell_noise_n) && s.load_cell_noise_n >= 0, "load_cell_noise_n");
  require(std::isfinite(s.load_cell_quantum_n) && s.load_cell_quantum_n >= 0,
          "load_cell_quantum_n");
}

double quantize(double value, double quantum) {
  if (quantum <= 0.0) return value;
  return std::round(value / quantum) * quantum;
}

Sensors::Sensors(const SensorParams& params, std::uint64_t seed) : params_(params), rng_(seed) {
  validate(params);
}

Measurement Sensors::measure(const JointTruth& truth) {
  Measurement m;
  m.x_in = quantize(truth.x_in, params_.motor_encoder_quantum_rad);
  m.x_out = params_.joint_encoder ? quantize(truth.x_out, params_.joint_encoder_quantum_rad)
                                  : std::numeric_limits<double>::quiet_NaN();
  const double sigma = params_.load_cell_noise_n;
  // Always draw both samples so the noise sequence does not depend on sigma == 0.
  const double n1 = noise_(rng_);
  const double n3 = noise_(rng_);
  m.T1 = quantize(truth.T1 + sigma * n1, params_.load_cell_quantum_n);
  m.T3 = quantize(truth.T3 + sigma * n3, params_.load_cell_quantum_n);
  return m;
}

}  // namespace tsmh::virtual_tissue_slave
