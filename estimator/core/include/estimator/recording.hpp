#pragma once
// Recorded data per the CSV contract of docs/data-formats.md:
// one joint's proximal measurements, optionally the measured distal torque.

#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "estimator/table.hpp"

namespace tsmh::estimator {

/// The pulley radii a recording (its '# radius_m:' comment, or --radius) may
/// give: a tenth of a millimetre to a metre. Beyond them the model's torques
/// overflow or the number is a typo.
inline constexpr double kMinRadiusM = 1e-4;
inline constexpr double kMaxRadiusM = 1.0;
inline constexpr const char* kRadiusRangeText =
    "a pulley radius in m within [0.0001, 1] (e.g. 0.01 for 10 mm)";

struct Recording {
  std::string source;                 ///< where it came from, for messages
  double radius_m = std::nan("");     ///< pulley radius R, m (NaN when unknown)
  std::vector<double> t;              ///< s, strictly increasing
  std::vector<double> x_in;           ///< rad, motor-side input pulley angle
  std::vector<double> tau_in;         ///< N m, proximal torque (empty when unknown)
  std::vector<double> tau_out;        ///< N m, measured distal torque (empty when unknown)
  std::vector<double> x_out;          ///< rad, joint angle (optional)
  std::vector<double> T1, T3;         ///< N, proximal tensions (optional)
  std::vector<double> xd_in, xdd_in;  ///< exact derivatives (optional)
  /// What the reader noticed but did not refuse (recording_checks.hpp): a
  /// header word that is not a contract column, times that look like ms.
  std::vector<std::string> warnings;
  std::vector<std::string> notes;  ///< what reading tolerated (Table::notes)

  std::size_t size() const { return t.size(); }
  bool has_tau_in() const { return !tau_in.empty(); }
  bool has_tau_out() const { return !tau_out.empty(); }
  bool has_derivatives() const { return !xd_in.empty() && !xdd_in.empty(); }
  bool has_x_out() const { return !x_out.empty() && x_out.size() == t.size(); }
  /// x_out at sample i, NaN where the recording has no joint angle.
  double x_out_at(std::size_t i) const {
    return has_x_out() ? x_out[i] : std::numeric_limits<double>::quiet_NaN();
  }
  /// Measured total friction F = (tau_in - tau_out)/R, N. Needs tau_in, tau_out, radius.
  std::vector<double> measured_friction() const;
};

struct RecordingRequirements {
  bool tau_in = false;   ///< tau_in (or T1 and T3) must be present
  bool tau_out = false;  ///< tau_out must be present
  bool radius = false;   ///< a radius must be known (file comment or override)
};

/// Throws DataError (the recording's source, no line) for the first of
/// `need` that `rec` does not meet, in the same words wherever a recording is
/// checked: read from a file here, or built by a program (fit, free motion).
void check_requirements(const Recording& rec, const RecordingRequirements& need);

/// Builds a Recording from a table read from the CSV contract. `radius_override`
/// (from --radius) wins over the file's "# radius_m:" comment. When tau_in is
/// absent but T1 and T3 are present, tau_in = R (T1 - T3). Validates time
/// strictly increasing and the requirements; throws DataError naming file,
/// line and column.
Recording recording_from_table(const Table& table, std::optional<double> radius_override,
                               const RecordingRequirements& need);

/// The table form of a recording (columns present in it, "radius_m" meta).
Table recording_to_table(const Recording& rec);

/// Convenience: read_csv_table + recording_from_table.
Recording read_recording_csv(const std::filesystem::path& path,
                             std::optional<double> radius_override = std::nullopt,
                             const RecordingRequirements& need = {});

/// Convenience: recording_to_table + write_csv_table (atomic).
void write_recording_csv(const Recording& rec, const std::filesystem::path& path);

}  // namespace tsmh::estimator
