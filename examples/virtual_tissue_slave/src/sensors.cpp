#include "virtual_tissue_slave/sensors.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "field_checks.hpp"

namespace tsmh::virtual_tissue_slave {

void validate(const SensorParams& s) {
  const FieldChecks check("sensor");
  check.non_negative(s.motor_encoder_quantum_rad, "motor_encoder_quantum_rad");
  check.non_negative(s.joint_encoder_quantum_rad, "joint_encoder_quantum_rad");
  check.non_negative(s.load_cell_noise_n, "load_cell_noise_n");
  check.non_negative(s.load_cell_quantum_n, "load_cell_quantum_n");
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
