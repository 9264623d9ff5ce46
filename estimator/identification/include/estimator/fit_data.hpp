#pragma once
// A recording made ready for identification: the motion (the file's exact
// derivatives, or by default the offline zero-phase smoother of the measured
// angle, or the deployed differentiator on request: FitDerivatives), the
// measured friction F = (tau_in - tau_out)/R, and a split of the samples
// into contiguous train and validation blocks.
//
// The model is always simulated over the whole record (its state needs the
// history); the split only says which samples are scored for the cost
// (train) and which for the report (validation). Alternate blocks put both
// early and late data, both directions and all amplitudes into each set.

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "estimator/differentiator.hpp"
#include "estimator/motion.hpp"
#include "estimator/offline_derivatives.hpp"
#include "estimator/recording.hpp"

namespace tsmh::estimator {

enum class SampleRole : std::uint8_t {
  kIgnored,     ///< warm-up: the model starts at rest, the real joint may not
  kTrain,       ///< scored by the identification cost
  kValidation,  ///< scored only by the report
};

/// Where the velocity and acceleration a fit sees come from.
enum class FitDerivatives : std::uint8_t {
  /// The file's exact xd_in/xdd_in when it has them, else `offline`.
  kAutomatic,
  /// Zero-phase RTS smoothing of the recorded angle (offline_derivatives.hpp):
  /// no lag, so the parameters found are the physical ones.
  kOffline,
  /// The deployed causal differentiator, as the haptic loop runs it (the
  /// parameters then also absorb its lag).
  kDeployed,
};

/// Name for reports: "exact", "offline" or "deployed" (what was actually used).
const char* derivatives_name(FitDerivatives d);
/// "auto", "offline" or "deployed"; throws std::invalid_argument otherwise.
FitDerivatives derivatives_from_name(const std::string& name);

struct SplitConfig {
  double block_s = 2.0;   ///< length of each block; shortened so each set has >= 3 blocks
  double warmup_s = 0.5;  ///< initial time scored by neither set
};

/// Minimum data identification accepts (docs/identification.md: "too short", "no motion").
struct DataRequirements {
  double min_duration_s = 4.0;
  std::size_t min_samples = 400;
  /// The angle must span at least this much, rad.
  double min_span_rad = 0.02;
  /// Velocity reversals (between |xd| > reversal_speed on both sides) needed.
  int min_reversals = 4;
  double reversal_speed = 0.05;  ///< rad/s
};

struct FitData {
  std::string source;  ///< file, for messages
  double radius_m = 0.0;
  std::vector<Motion> motion;    ///< every sample, as deployed
  std::vector<double> measured;  ///< F, N
  std::vector<SampleRole> role;  ///< per sample
  double block_s = 0.0;          ///< block length actually used
  int reversals = 0;             ///< velocity reversals found (a data-quality figure)
  /// Where xd, xdd came from: "exact" (file columns), "offline" or "deployed".
  std::string derivatives;

  std::size_t size() const { return motion.size(); }
  std::size_t count(SampleRole r) const;
  double duration() const { return motion.empty() ? 0.0 : motion.back().t - motion.front().t; }
  /// 1 where role == r, else 0 (a cost weight per sample).
  std::vector<double> weights(SampleRole r) const;
};

/// Checks `rec` for identification and builds FitData. Throws DataError naming
/// file and column (and the sample, for data that did not come from a CSV
/// reader that checked it already): missing tau_in/tau_out/radius, non-finite
/// values, too short, no motion.
FitData prepare_fit_data(const Recording& rec, const SplitConfig& split = {},
                         const DataRequirements& need = {}, const DifferentiatorConfig& diff = {},
                         FitDerivatives derivatives = FitDerivatives::kAutomatic,
                         const OfflineDerivativeConfig& offline = {});

/// Velocity reversals in `motion`: sign changes of xd between excursions
/// beyond +-speed (a Schmitt trigger, so encoder noise near rest does not count).
int count_reversals(std::span<const Motion> motion, double speed);

}  // namespace tsmh::estimator
