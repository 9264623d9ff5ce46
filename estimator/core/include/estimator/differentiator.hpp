#pragma once
// Online differentiation of a sampled, quantised angle into velocity,
// acceleration and the sign of the acceleration, causally (the haptic loop
// and `tsm simulate` run exactly this, sample by sample).
//
// Four polynomial Kalman filters on the same samples, each discretised for
// the actual interval (uneven time stamps and dropped samples are exact):
// - the velocity channel (white jerk, about 12 Hz) gives x and xd;
// - the acceleration channel (white snap, a few Hz, zero lag on constant
//   jerk) gives xdd and its own uncertainty;
// - the fine acceleration channel (white crackle, the fifth derivative: a
//   smoother motion model that predicts a hand's curving acceleration
//   further) resolves the accelerations of smooth motion more finely;
// - the slow acceleration channel (white jerk of tiny density: nearly
//   constant acceleration) resolves the small, lasting accelerations of slow
//   motion that the acceleration channel's noise buries.
// sgn(xdd), on which eq. (4) and the branches of eqs. (5)-(10) switch, is by
// default the expected sign across the estimate's uncertainty (SignMode):
// from the fine channel where it agrees with the fast one, from the slow
// channel where that agrees too, else from the fast one (a manoeuvre the
// smoother models lag). That is the whole filter: the corrections that add
// assumptions about the motion (rest, cruise, hindsight) are their own
// component (corrections.hpp). Delay, noise and accuracy are measured in
// docs/friction-model.md.

#include <array>
#include <cstddef>
#include <limits>
#include <optional>
#include <string_view>
#include <vector>

#include "estimator/poly_kalman.hpp"
#include "estimator/reference_encoder.hpp"

namespace tsmh::estimator {

/// How sgn(xdd) is decided from the acceleration estimate.
enum class SignMode {
  /// -1, 0 or +1, the paper's model as written: +-1 beyond `sign_sigmas`
  /// standard deviations, held inside the release band for `sign_hold`, then 0.
  kHard,
  /// The expected sign across the estimate's uncertainty, a ramp
  /// clamp(xdd / (smooth_sigmas sd), -1, 1): no decision delay at a zero
  /// crossing and no chatter; +-1 once the sign is certain. The default: the
  /// server and `tsm simulate` use it (docs/friction-model.md has all three).
  /// Where the slow channel agrees with the fast one, its sign (see
  /// slow_jerk_psd).
  kSmooth,
  /// kSmooth from the fast channel alone (no fine or slow channel; for
  /// comparison).
  kSmoothFast,
};

/// "smooth", "smooth-fast" or "hard" (the server config's `sign`, `tsm
/// simulate --sign`); nullopt for anything else.
inline std::optional<SignMode> sign_mode_from_name(std::string_view name) {
  if (name == "smooth") return SignMode::kSmooth;
  if (name == "smooth-fast") return SignMode::kSmoothFast;
  if (name == "hard") return SignMode::kHard;
  return std::nullopt;
}

struct DifferentiatorConfig {
  /// Velocity channel (x, xd): spectral density of the jerk, (rad/s^3)^2/Hz.
  /// Larger follows faster motion with less lag and more noise.
  double jerk_psd = 300.0;
  /// Acceleration channel (xdd and its uncertainty): spectral density of the
  /// snap, (rad/s^4)^2/Hz.
  double snap_psd = 3200.0;
  /// Fine acceleration channel (white crackle: x, xd, xdd, jerk, snap),
  /// spectral density of the fifth derivative, (rad/s^5)^2/Hz; 0: off
  /// (smooth sign only). On smooth motion it resolves the acceleration about
  /// twice as finely as the snap model; a manoeuvre (a reversal, the start or
  /// end of a move) it follows late, and there the fast channel decides.
  double fine_psd = 1e5;
  /// Smooth sign: the fine channel decides while the fast estimate lies
  /// within this many of the fast channel's standard deviations of it
  /// (blended quadratically out to that distance, like slow_consistency).
  double fine_consistency = 3.0;
  /// Slow acceleration channel (white jerk), (rad/s^3)^2/Hz; 0: off. It
  /// resolves the small, lasting accelerations of slow motion, which decide
  /// the direction of eq. (4)'s drive below |xd| = lambda and which the fast
  /// channel's noise buries (smooth sign only).
  double slow_jerk_psd = 1e-3;
  /// Smooth sign: the slow channel decides while the fast estimate lies
  /// within this many of its standard deviations of the slow one (blended
  /// quadratically out to that distance); beyond it, the fast channel.
  double slow_consistency = 1.5;
  /// Smooth sign from the slow channel: +-1 beyond this many of its sd.
  double slow_sigmas = 1.0;
  /// Encoder quantum, rad; its uniform error (quantum^2/12) is the measurement
  /// noise together with position_noise.
  double quantum = kReferenceQuantum;
  /// Additional white measurement noise on the angle, rad (standard deviation).
  double position_noise = 0.0;
  SignMode sign_mode = SignMode::kSmooth;
  /// Smooth sign: |xdd| at which the sign is +-1, in standard deviations.
  double smooth_sigmas = 0.3;
  /// Hard sign: +-1 beyond this many standard deviations, released below
  /// sign_release of them after sign_hold seconds.
  double sign_sigmas = 3.0;
  double sign_release = 2.0;
  double sign_hold = 0.1;
  /// Hard sign: a fixed |xdd| threshold, rad/s^2, instead of the
  /// uncertainty-scaled one (negative: scaled, the default).
  double acc_sign_threshold = -1.0;
  /// A gap longer than this (s) restarts the filters at the new sample.
  double max_gap = 0.05;
  /// true: the full Kalman recursion every sample (covariance propagated for
  /// the actual interval). false: each channel's steady-state gain for the
  /// actual interval, from a table made at construction (interpolated in
  /// 25 us steps up to 4 ms, coarser up to max_gap): the same filter once it
  /// has settled, at a fraction of the cost. Measured against each other in
  /// docs/friction-model.md.
  bool exact_covariance = false;
};

/// The range of the differentiator setting a user may change (the encoder's
/// resolution), shared by haptic-server's key and `tsm simulate`'s option so
/// that both accept the same configurations.
struct DifferentiatorLimits {
  /// rad
  static constexpr double kEncoderQuantum = 0.1;
  /// What is wrong with `q` as an encoder quantum, rad, for a command line's
  /// message; nullptr when it is usable.
  static constexpr const char* encoder_quantum_problem(double q) noexcept {
    static_assert(kEncoderQuantum == 0.1, "the text below");
    return q > 0.0 && q <= kEncoderQuantum ? nullptr : "must be within (0, 0.1] rad";
  }
};

struct Derivatives {
  double x = 0.0;       ///< filtered angle, rad
  double xd = 0.0;      ///< rad/s
  double xdd = 0.0;     ///< rad/s^2
  double acc_sign = 0;  ///< sgn(xdd) (-1, 0, +1), or its expected value (smoothed sign)
  double acc_sd = 0.0;  ///< standard deviation of xdd, rad/s^2
  bool valid = false;   ///< false for a rejected sample (non-finite, time not increasing)
};

class Differentiator {
 public:
  explicit Differentiator(const DifferentiatorConfig& config = {});

  /// Feeds the sample (t in s, x in rad). Never allocates or throws.
  /// Non-finite input or t <= last t is rejected: state unchanged, valid = false.
  Derivatives update(double t, double x) noexcept;
  void reset() noexcept;

  const DifferentiatorConfig& config() const { return cfg_; }

  /// The steady-state gains for a sample interval dt > 0 as update() uses
  /// them once the filters have settled (interpolated from the table; all 0
  /// with exact_covariance). For tests and diagnostics: each channel then is
  /// PolyKalman::update_with_gain with its gain (test_differentiator.cpp).
  struct SteadyGains {
    PolyKalman<3>::Vec velocity{}, slow{};
    PolyKalman<4>::Vec acceleration{};
    PolyKalman<5>::Vec fine{};
    double acc_sd = 0.0;                ///< sd of xdd, rad/s^2
    double inv_width = 0.0;             ///< 1 / (smooth_sigmas acc_sd)
    double fine_inv_width = 0.0;        ///< 1 / (smooth_sigmas fine sd); 0 without the fine channel
    double inv_fine_consistency = 0.0;  ///< 1 / (fine_consistency acc_sd)
    double slow_inv_width = 0.0;        ///< 1 / (slow_sigmas slow sd); 0 without the slow channel
    double inv_consistency = 0.0;       ///< 1 / (slow_consistency acc_sd)
  };
  SteadyGains steady_gains(double dt) const noexcept;
  const Derivatives& last() const { return out_; }

  /// The fine channel's acceleration `back` s before the last sample,
  /// extrapolated from its state now (xdd - back jerk + back^2 / 2 snap):
  /// in hindsight, well inside the channel's memory, where its estimate is
  /// best. NaN without the fine channel or before the first sample.
  double fine_acceleration_before(double back) const noexcept {
    if (!use_fine_ || !started_) return std::numeric_limits<double>::quiet_NaN();
    // steady_: the steady-state gains run (never with exact_covariance).
    const double xdd = steady_ ? acc_fine_state_[5] : fine_.state()[2];
    const double jerk = steady_ ? acc_fine_state_[7] : fine_.state()[3];
    const double snap = steady_ ? fine_snap_ : fine_.state()[4];
    return xdd - back * jerk + 0.5 * back * back * snap;
  }
  /// The acceleration channel's innovation at the last sample (the sample
  /// less its prediction), rad, and the variance its model predicted for it,
  /// P[0][0] + r = r / (1 - K[0]), rad^2: how consistent the motion is with
  /// that model (the cruise correction's test).
  double acceleration_innovation() const noexcept { return acc_innovation_; }
  double acceleration_innovation_variance() const noexcept { return r_ / (1.0 - acc_gain0_); }
  /// The measurement noise's variance, rad^2: quantum^2/12 + position_noise^2.
  double measurement_variance() const noexcept { return r_; }
  /// Whether the last accepted sample (re)started the filters: the first
  /// one, or one after a gap longer than max_gap.
  bool restarted() const noexcept { return restarted_; }

 private:
  void start(double t, double x) noexcept;
  struct Step;
  double decide_sign(const Step& step, double dt) noexcept;

  DifferentiatorConfig cfg_;
  double r_;  // measurement variance, rad^2
  PolyKalman<3> velocity_;
  PolyKalman<4> acceleration_;
  PolyKalman<3> slow_;
  PolyKalman<5> fine_;
  // The slow and fine channels run only where they decide something: the
  // smooth sign with slow_jerk_psd > 0, fine_psd > 0.
  bool use_slow_;
  bool use_fine_;
  // Steady-state gains by interval (exact_covariance false): node k is for
  // the interval grid_dt(k); see gain_for(). A row holds the four
  // channels' gains and what decide_sign() needs; the velocity and slow
  // gains are interleaved ({velocity[i], slow[i]}) because the steady-state
  // step advances those two channels (both white jerk, the same F(dt))
  // side by side, as pairs of doubles; so are the acceleration and fine
  // channels' first four ({acceleration[i], fine[i]}).
  static constexpr std::size_t kGainPairs = 0;        // 3 pairs {velocity[i], slow[i]}
  static constexpr std::size_t kGainAccFine = 6;      // 4 pairs {acceleration[i], fine[i]}
  static constexpr std::size_t kGainFine4 = 14;       // fine[4]
  static constexpr std::size_t kFineInvWidth = 15;    // 1 / (smooth_sigmas fine sd)
  static constexpr std::size_t kSlowInvWidth = 16;    // 1 / (slow_sigmas slow sd)
  static constexpr std::size_t kInvConsistency = 17;  // 1 / (slow_consistency acc_sd)
  static constexpr std::size_t kAccSd = 18;
  static constexpr std::size_t kInvWidth = 19;            // 1 / (smooth_sigmas acc_sd)
  static constexpr std::size_t kInvFineConsistency = 20;  // 1 / (fine_consistency acc_sd)
  static constexpr std::size_t kGainFields = 22;          // one spare: fields are read in pairs
  using GainRow = std::array<double, kGainFields>;
  // A node's row and the step to the next node's (next - this, as the
  // interpolation would form it): interpolating is then one multiply-add per
  // field, from one place in memory.
  struct GainNode {
    alignas(16) GainRow at;
    alignas(16) GainRow step;
  };
  std::vector<GainNode> gains_;
  double coarse_inverse_step_ = 0.0;
  int settling_ = 0;  // samples of full recursion left after a (re)start
  void build_gain_table();
  double grid_dt(std::size_t k) const noexcept;
  double gain_last_ = 0.0;  // gains_.size() - 1
  double gain_position(double dt) const noexcept;
  // The gains for the interval dt, interpolated between nodes (for
  // steady_gains(); the steady-state step forms them itself).
  GainRow gain_for(double dt) const noexcept;
  // One sample's filtered values and what decide_sign() needs.
  struct Step {
    double x, xd, xdd, slow_xdd, fine_xdd;
    double acc_sd, inv_width, slow_inv_width, inv_consistency;
    double fine_inv_width, inv_fine_consistency;
    // The acceleration channel's innovation and K[0].
    double acc_innovation, acc_gain0;
  };
  Step full_step(double dt, double x) noexcept;
  // The filters' state while the steady-state gains run: the velocity and
  // slow channels interleaved like their gains, then the acceleration and
  // fine channels likewise, then the fine channel's fifth. The full
  // recursion keeps it in the PolyKalman objects; it is copied here once,
  // when the gains take over (steady_).
  void enter_steady() noexcept;
  Step steady_step(double dt, double z) noexcept;
  alignas(16) std::array<double, 6> pair_state_{};
  alignas(16) std::array<double, 8> acc_fine_state_{};
  double fine_snap_ = 0.0;
  bool steady_ = false;
  // The acceleration channel's last innovation and K[0].
  double acc_innovation_ = 0.0, acc_gain0_ = 0.0;
  double in_band_ = 0.0;  // how long |xdd| has been inside the release band, s
  bool started_ = false;
  bool restarted_ = false;
  double t_ = 0.0;
  Derivatives out_;
};

}  // namespace tsmh::estimator
