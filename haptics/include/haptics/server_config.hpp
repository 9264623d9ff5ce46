#pragma once
// The haptic-server configuration file (YAML, docs/haptic-server.md). Every
// field is validated on load; an error names the file and the field, e.g.
// "server.yaml: joints[1].max_torque_nm: must be a number > 0".

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

#include "bridge/limits.hpp"
#include "config/field_reader.hpp"
#include "estimator/estimator_settings.hpp"
#include "haptics/haptic_loop.hpp"
#include "master_devices/device.hpp"

namespace tsmh::haptics {

/// Bad configuration; the message names file, field and line. The same type
/// as the device drivers' settings errors, so one catch covers both.
using ConfigError = config::ConfigError;

struct JointConfig {
  std::string name;
  std::string params = "paper";  ///< friction model: preset or params YAML (resolved path)
  double radius_m = 0.01;
  /// The online estimator's settings (sign mode, differentiator knobs,
  /// start state): the same settings and limits as `tsm simulate`'s flags.
  estimator::EstimatorSettings estimator;
};

struct RealtimeConfig {
  bool sched_fifo = true;  ///< try SCHED_FIFO; fall back with a warning when not permitted
  int priority = 80;
  bool lock_memory = true;      ///< mlockall; fall back with a warning when not permitted
  int cpu = -1;                 ///< pin the loop thread to this CPU (-1: no pinning)
  bool cpu_dma_latency = true;  ///< hold /dev/cpu_dma_latency at 0 while running
};

struct EvaluationConfig {
  bool truth = false;          ///< subscribe SLAVE_TRUTH (virtual slave) to evaluate the estimate
  std::string trace;           ///< per-tick CSV path ("" = none)
  std::string report;          ///< JSON report path ("" = none)
  double max_trace_s = 600.0;  ///< trace storage, allocated before the loop starts
};

struct ServerConfig {
  std::string source;  ///< the file it came from, for messages
  LoopConfig loop;
  std::vector<JointConfig> joints;
  std::string device_driver = "sim";
  YAML::Node device_settings;  ///< passed to the driver unchanged
  std::string lcm_url;         ///< "" = --lcm-url / LCM_DEFAULT_URL / default
  std::string lcm_prefix;
  double duration_s = 0.0;  ///< 0 = until SIGINT/SIGTERM
  RealtimeConfig realtime;
  EvaluationConfig evaluation;
  /// `slave_state:` how fast the slave's values can physically change
  /// (bridge/limits.hpp); a faster step rejects the message.
  bridge::SlaveStateLimits slave_limits;
};

/// Parses YAML text; relative paths (params, trace, report) resolve against
/// `base_dir`. Throws ConfigError naming `origin` and the field.
ServerConfig parse_server_config(const std::string& yaml_text, const std::string& origin,
                                 const std::filesystem::path& base_dir);
ServerConfig load_server_config(const std::filesystem::path& path);

/// The configuration against the device it opened: no more joints than the
/// device has axes. Throws ConfigError naming the file.
void check_against_device(const ServerConfig& c, const master_devices::DeviceSpec& spec);

FeedbackSource feedback_source_from_string(const std::string& s);  ///< throws ConfigError

}  // namespace tsmh::haptics
