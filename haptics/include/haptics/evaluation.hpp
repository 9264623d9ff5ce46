#pragma once
// What a run of the server achieved, from its trace: loop timing, how close
// the fed-back distal torque was to the truth (estimated vs naive), and the
// stiffness a surgeon would perceive for soft tissue and for the nodule
// beside the true values. Written as the demo report (docs/data-formats.md).

#include <limits>
#include <string>
#include <vector>

#include "haptics/haptic_loop.hpp"
#include "haptics/server_config.hpp"
#include "haptics/trace.hpp"
#include "realtime/histogram.hpp"

namespace tsmh::haptics {

struct JointEvaluation {
  std::string name;
  std::size_t samples = 0;      ///< enabled ticks with matched truth
  double rmse_estimated = 0.0;  ///< N m, tau_out_est vs true tau_out
  double rmse_naive = 0.0;      ///< N m, tau_in vs true tau_out
  double ratio = 0.0;           ///< rmse_estimated / rmse_naive
  double true_peak = 0.0;       ///< N m, max |true tau_out|
  /// Free motion: ticks where |true tau_out| < kPhantomThreshold. What the
  /// surgeon feels there is phantom torque (the truth is about zero).
  std::size_t free_samples = 0;
  double deepest_indentation = 0.0;  ///< m, deepest tissue indentation seen (SLAVE_TRUTH)
  double phantom_rendered = 0.0;     ///< N m on the master, rms of the torque written
  double phantom_naive = 0.0;        ///< N m on the master, rms of force_scale * tau_in
  double phantom_ratio = 0.0;        ///< phantom_rendered / phantom_naive
  /// In contact: ticks where the tip indents the tissue (SLAVE_TRUTH's
  /// indentation > 0; without one, |true tau_out| >= kPhantomThreshold).
  /// The error there is what the surgeon feels the tissue by; free motion
  /// (the ticks above) is where it shows as phantom torque instead.
  std::size_t contact_samples = 0;
  double contact_rmse_estimated = 0.0;  ///< N m, tau_out_est vs true tau_out
  double contact_rmse_naive = 0.0;      ///< N m, tau_in vs true tau_out
  double contact_ratio = 0.0;           ///< contact_rmse_estimated / contact_rmse_naive
  double free_rmse_estimated = 0.0;     ///< N m, over the free-motion ticks
  double free_rmse_naive = 0.0;         ///< N m, over the free-motion ticks
};

/// |true distal torque| below which a tick counts as free motion, N m.
inline constexpr double kPhantomThreshold = 0.005;

/// Stiffness in slave joint space, N m/rad: perceived = slope of the rendered
/// master torque against master angle, divided by force_scale * position_scale;
/// true = slope of the true distal torque against the true joint angle, over
/// the same samples.
struct Stiffness {
  double perceived = 0.0;
  double truth = 0.0;
  /// What a perfect estimate would have felt: the true distal torque against
  /// the master angle / position_scale (differs from truth by the slave's
  /// tracking under load).
  double ideal = 0.0;
  std::size_t samples = 0;
  /// False: too few samples of this phase for a slope, or (the nodule) the
  /// press never reached a stiffer layer; the figures are then NaN and
  /// `why` says which.
  bool reached = false;
  std::string why;
};

/// Fewest contact ticks a stiffness is computed from (0.5 s at 1 kHz): below
/// it a slope rests on part of one press (133 ticks gave +75 %).
inline constexpr std::size_t kMinStiffnessSamples = 500;
/// The deeper phase counts as the nodule only when its true slope is this
/// many times the soft layer's: otherwise the split fell inside one layer.
inline constexpr double kNoduleSlopeRatio = 2.0;

struct Discrimination {
  int joint = -1;               ///< the joint that pressed the tissue (-1: no contact seen)
  double force_scale = 1.0;     ///< of that joint: master N m per slave N m
  double force_sign = 1.0;      ///< of that joint (the master renders -sign x scale x tau)
  double position_scale = 1.0;  ///< of that joint: slave rad per master rad
  double boundary_m = 0.0;  ///< indentation separating soft layer from nodule (NaN: not reached)
  double deepest_m = 0.0;   ///< deepest indentation of the pressing joint, m
  Stiffness soft, hard;
};

/// A drift alarm or recalibration event, as the server logged it.
struct CalibrationRecord {
  double t_s = 0.0;    ///< since the server started
  std::string kind;    ///< drift_alarm, drift_cleared, requested, applied, refused
  int joint = -1;      ///< -1: every joint concerned
  double scale = 1.0;  ///< drift: the scale the data ask for; applied: the new scale
  std::string reason;  ///< refused: why
  /// applied: the levels' scales sliding positive / negative (both = scale
  /// when one common scale was fitted); NaN for the other kinds.
  double scale_positive = std::numeric_limits<double>::quiet_NaN();
  double scale_negative = std::numeric_limits<double>::quiet_NaN();
};

struct EvaluationReport {
  double rate_hz = 0.0;  ///< measured mean rate
  double nominal_rate_hz = 0.0;
  realtime::HistogramSummary jitter;
  realtime::HistogramSummary compute;
  std::uint64_t overruns = 0;
  double duration_s = 0.0;
  std::string feedback;
  std::vector<JointEvaluation> joints;
  Discrimination discrimination;
  std::vector<CalibrationRecord> calibration;  ///< filled by the server (report "calibration")
  std::vector<double> friction_scale;  ///< per joint, at the end (mean of the two directions)
  std::vector<double> friction_scale_positive;  ///< per joint, at the end, sliding xd >= 0
  std::vector<double> friction_scale_negative;  ///< per joint, at the end, sliding xd < 0
};

EvaluationReport evaluate(const HapticLoop& loop, const Trace& trace, const ServerConfig& config);

/// One joint's torque figures (rmse estimated/naive, free-motion phantom torque).
JointEvaluation evaluate_joint(const Trace& trace, const ServerConfig& config, std::size_t joint);

/// The stiffness part alone, for the pressing joint `joint` (-1: none).
Discrimination discriminate(const Trace& trace, const ServerConfig& config, int joint);

/// Slope of y against x by least squares with intercept (NaN when degenerate).
double slope(const std::vector<double>& x, const std::vector<double>& y);

void write_report(const EvaluationReport& report, const std::string& path);  ///< JSON, atomic
std::string format_report(const EvaluationReport& report);                   ///< human summary
/// The stiffness lines of the summary; a phase not reached says why, never a number.
std::string format_stiffness(const Discrimination& d, double rate_hz);
std::string report_to_json(const EvaluationReport& report);

}  // namespace tsmh::haptics
