#pragma once
// LCM logs as DATA for `tsm` (docs/data-formats.md): one joint of the SLAVE_STATE
// stream (with SLAVE_TRUTH's tau_out matched by seq), read by the bridge
// module and turned into the same Recording a CSV gives.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <optional>
#include <string>

#include "data_sources.hpp"
#include "estimator/recording.hpp"

namespace tsmh::tsm_cli {

/// Which joint and which arm (channel prefix) of a log to read.
struct LcmLogSelection {
  int joint = 0;
  std::string prefix;  ///< e.g. "ARM1_"; empty: SLAVE_STATE, SLAVE_TRUTH
  /// --accept-truncated: use the intact events of a log that was cut off (or
  /// has corrupt regions), saying how many were lost; otherwise an error.
  bool accept_truncated = false;
  /// --key: verify the MAC of every event with this link key (default: the
  /// key search of docs/bridge.md; none found: unsigned logs only).
  std::string key_file;
  /// --skip-mac: use events without checking their MAC.
  bool skip_mac = false;
};

/// Reads joint `sel.joint` of `sel.prefix`SLAVE_STATE (+ SLAVE_TRUTH) from an
/// LCM log. tau_in = R (T1 - T3) with R from the log's radius_m unless
/// `radius_override`. Throws estimator::DataError naming the file (and what
/// is wrong in it). `summary`, when given, receives what was read and left out.
estimator::Recording recording_from_lcm_log(const std::filesystem::path& path,
                                            const LcmLogSelection& sel,
                                            std::optional<double> radius_override,
                                            const estimator::RecordingRequirements& need,
                                            std::string* summary = nullptr);

/// The "lcm-log" data source: accepts files starting with LCM's log sync word.
/// `sel` is read when a file is loaded, so options parsed later apply.
DataSource lcm_log_source(const LcmLogSelection& sel);

/// Adds --joint, --prefix (which part of an LCM log DATA is), --accept-truncated,
/// --key and --skip-mac to `cmd`.
void add_lcm_log_options(CLI::App& cmd, LcmLogSelection& sel);

}  // namespace tsmh::tsm_cli
