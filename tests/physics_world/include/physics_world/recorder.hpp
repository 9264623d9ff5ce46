#pragma once
// A run of the world through its sensors, as the recording CSV contract
// (docs/data-formats.md) has it, plus what only a simulator knows: the true
// sheath friction (tau_in - tau_out)/R without noise, the true torques, and
// whether the tip touched something.

#include <cstdint>
#include <filesystem>
#include <vector>

#include "estimator/recording.hpp"
#include "estimator/table.hpp"
#include "physics_world/motion.hpp"
#include "physics_world/world.hpp"

namespace tsmh::physics_world {

struct SensorConfig {
  double encoder_counts = 40960.0;  ///< per turn, both encoders (x_in, x_out)
  double load_cell_noise_n = 0.3;   ///< white noise of each tension load cell, N
  /// Noise of the tip torque sensor a calibration rig adds, N m (0.3 N on each
  /// distal tension, as R sqrt(2) 0.3 N).
  double tip_torque_noise_n_m = 0.3 * 1.4142135623730951 * 0.01;
};

struct RunConfig {
  MotionKind kind = MotionKind::kMultisine;
  std::uint64_t motion_seed = 1;  ///< the path, the external torque, the noise, the re-route
  double duration_s = 40.0;
  double rate_hz = 1000.0;
  SensorConfig sensors;
};

struct WorldRecording {
  /// What the sensors saw: t, x_in, tau_in = R (T1 - T3) (measured), tau_out
  /// (the tip sensor), x_out, T1, T3 (measured), and the exact xd_in, xdd_in
  /// of the prescribed motion.
  estimator::Recording recording;
  std::vector<double> friction_true;  ///< N, (tau_in - tau_out)/R of the true tensions
  std::vector<double> tau_in_true;    ///< N m, R (T1 - T3) without noise
  std::vector<double> tau_out_true;   ///< N m, R (T2 - T4): the torque the tendons give the tip
  std::vector<double> contact;        ///< 1 where tissue or the grasped object pushes back
  WorldParams world;                  ///< as run (with the re-route of a kReroute run)
};

/// Runs `world` from rest for the configured motion. Throws
/// std::invalid_argument for bad parameters.
WorldRecording record(const WorldParams& world, const RunConfig& run);

/// The recording's table with the truth columns friction_true,
/// tau_in_true, tau_out_true and contact (extra columns the CSV contract's
/// readers ignore).
estimator::Table to_table(const WorldRecording& r, bool with_derivatives = false);
void write_csv(const WorldRecording& r, const std::filesystem::path& path,
               bool with_derivatives = false);

}  // namespace tsmh::physics_world
