#pragma once
// Identification of a friction model's parameters from recorded data
// (`tsm fit`): least squares between the measured friction and the
// model simulated on the data's motion (fit_data.hpp: exact or offline
// zero-phase derivatives by default), on the train samples only.
//
// Default method "lm": informed starts from the data (sliding
// plateaus give the levels, reversal slopes gamma theta, a small grid over
// theta's share, lambda and the Stribeck decay), each screened by a few
// Levenberg-Marquardt iterations on data decimated to 5 ms; the best
// `starts` candidates are polished by Levenberg-Marquardt on the full-rate
// data (forward-difference Jacobian, columns spread over the threads, a weak
// prior towards the start that only decides directions the data leaves
// undetermined). The model is smooth in its parameters for a fixed motion,
// so this converges where derivative-free searches stopped in local optima.
// Method "nlopt" keeps the previous optimiser: per start an MLSL global stage
// on decimated data, BOBYQA polishes, seeded starts on worker threads.
// Both work in normalised coordinates (parameter_map.hpp) within the
// parameters' bounds, and the result depends on the data and options only,
// never on the thread count or timing (docs/identification.md).

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "estimator/fit_data.hpp"
#include "estimator/friction_model.hpp"
#include "estimator/parameter_map.hpp"

namespace tsmh::estimator {

struct FitProgress {
  const char* stage = "";  ///< "global", "local", "done"
  int starts_done = 0;
  int starts_total = 0;
  long evaluations = 0;
  double best_rmse = 0.0;  ///< on train samples so far, N (NaN before the first)
  double elapsed_s = 0.0;
};

struct FitOptions {
  /// "lm" (default): informed multi-start screening on decimated data, then
  /// Levenberg-Marquardt on the full-rate data from the best `starts`
  /// candidates (see identify()). "nlopt": the NLopt MLSL + BOBYQA path
  /// configured by the global_* and *_evaluations fields below.
  std::string method = "lm";
  std::uint64_t seed = 1;
  /// lm: candidates polished on the full-rate data; nlopt: independent starts.
  int starts = 4;
  /// Worker threads; 0: std::thread::hardware_concurrency().
  int threads = 0;
  /// false: local polish only, from the initial values (start 0) and from
  /// small perturbations of them (other starts): a warm refit.
  bool global_stage = true;
  /// Distributed slip: solve the tension and load copies wherever the data
  /// vary their quantities (separable_fit.hpp). tsm gap turns it off, to
  /// add those effects one at a time and name them.
  bool slip_copies_from_data = true;
  /// NLopt algorithm of the global stage, by NLopt's name (GN_CRS2_LM,
  /// GN_ESCH, GN_ISRES, G_MLSL_LDS, ...).
  std::string global_algorithm = "G_MLSL";
  int global_population = 0;           ///< 0: NLopt's default
  int mlsl_local_evaluations = 150;    ///< per local search of an MLSL global stage
  int global_evaluations = 2000;       ///< per start, decimated data
  int coarse_local_evaluations = 400;  ///< per start, BOBYQA on the decimated data
  int local_evaluations = 150;         ///< per start, BOBYQA on the full-rate data
  /// Sample period of the decimated data the global stage scores, s (0: full rate).
  double global_sample_period_s = 0.005;
  /// Spread of the perturbed starts of a warm refit, in normalised units.
  double warm_perturbation = 0.08;
  /// Further starting points (full value vectors, as parameters() orders
  /// them), tried after the initial values; e.g. candidate step times.
  std::vector<std::vector<double>> extra_starts;
  /// Narrower search bounds for some parameters; the model's own bounds
  /// still apply. Time parameters (unit "s", a step time) are always
  /// searched within the recording.
  std::vector<BoundsOverride> bounds;
  /// lm: Levenberg-Marquardt iterations per screened start (decimated data)
  /// and per polished candidate (full-rate data).
  int screen_iterations = 10;
  int polish_iterations = 25;
  /// lm: weight of a weak prior pulling every free parameter (normalised
  /// coordinates) towards its start, relative to the measurement-noise
  /// variance: a full-range move costs this fraction of the noise variance.
  /// It only decides directions the data leaves undetermined (e.g. mu2 vs
  /// kappa2); the report names the parameters it held.
  double prior_weight = 1e-3;
  /// Called from the calling thread every progress_interval_s while working.
  std::function<void(const FitProgress&)> progress;
  double progress_interval_s = 0.25;
};

struct StartOutcome {
  int index = 0;
  double global_rmse = 0.0;  ///< after the global stage (decimated data), N
  double rmse = 0.0;         ///< after the polish, train samples, N
  long evaluations = 0;
  double seconds = 0.0;
  std::string stop_reason;  ///< of the polish, from NLopt
};

struct FitResult {
  std::unique_ptr<FrictionModel> model;  ///< the fitted model
  std::vector<double> values;            ///< all parameter values (parameters() order)
  std::vector<double> simulated;         ///< fitted F over the whole record, N
  double train_rmse = 0.0;               ///< N
  std::vector<StartOutcome> starts;
  int best_start = 0;
  long evaluations = 0;
  double seconds = 0.0;
  std::string global_algorithm;  ///< NLopt's name or "informed multi-start"; empty when not used
  std::string local_algorithm;
  std::string library;  ///< "NLopt" or "own Levenberg-Marquardt"
  /// Starting points the lm method screened, and how they were chosen.
  int screened = 0;
  std::vector<std::string> notes;
};

/// Fits the free parameters of `initial` (cloned) to `data`. Throws
/// std::invalid_argument when the model has no free parameters.
FitResult identify(const FrictionModel& initial, const FitData& data,
                   const FitOptions& options = {});

/// Mean squared error on the samples with weight 1 (weights 0/1).
double weighted_mse(std::span<const double> measured, std::span<const double> model,
                    std::span<const double> weights) noexcept;

/// For the tendon-sheath model: core.gamma is fixed because (gamma c,
/// theta / c, every level / c) gives exactly the same friction, so its value
/// only sets the scale of the levels. When the data's friction scale would
/// need levels outside [0.1, 5] (near their bounds), this sets gamma to that
/// scale, which multiplies the start model's friction by the same factor
/// (theta and the levels unchanged). Returns a note for the report, empty
/// when nothing was done. Other model kinds are left unchanged.
std::string adapt_scale_to_data(FrictionModel& model, const FitData& data);

}  // namespace tsmh::estimator
