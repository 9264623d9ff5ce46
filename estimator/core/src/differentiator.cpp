#include "estimator/differentiator.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>

namespace tsmh::estimator {
namespace {

constexpr double kFineStep = 25e-6;  // s, grid step up to kFineEnd
constexpr std::size_t kFine = 160;   // 25 us ... 4 ms
constexpr double kFineEnd = kFineStep * kFine;
constexpr std::size_t kCoarse = 200;  // kFineEnd ... max_gap
// Samples of full recursion after a (re)start, while the covariance falls
// from the start-up prior to its steady state (about 0.1 s at 1 kHz).
constexpr int kSettlingSamples = 100;
// The cruise hypothesis: the acceleration channel's normalised innovation
// squared is averaged over this time (s) before it is held against
// cruise_nis; fewer samples than kMinWindowSamples in the window: no test.
constexpr double kNisTime = 0.005;
constexpr std::size_t kMinWindowSamples = 8;
// The window's power sums are moved sample by sample (O(1)) and rebuilt from
// the samples this often, before rounding can accumulate.
constexpr int kRebuildSamples = 500;
// Spread of the acceleration (rad/s^2) and jerk (rad/s^3) of a moving hand
// or motor, the alternative to the cruise hypothesis: its Bayes factor
// weighs how much of that spread the window's fit leaves possible.
constexpr double kMovingAccSd = 10.0;
constexpr double kMovingJerkSd = 300.0;

double measurement_variance(const DifferentiatorConfig& c) {
  const double r = c.quantum * c.quantum / 12.0 + c.position_noise * c.position_noise;
  return r > 0.0 ? r : 1e-12;
}

Derivatives invalidated(Derivatives last) noexcept {
  last.valid = false;
  return last;
}

}  // namespace

Differentiator::Differentiator(const DifferentiatorConfig& config)
    : cfg_(config),
      r_(measurement_variance(config)),
      velocity_(config.jerk_psd, r_),
      acceleration_(config.snap_psd, r_),
      slow_(config.slow_jerk_psd > 0.0 ? config.slow_jerk_psd : 1.0, r_),
      fine_(config.fine_psd > 0.0 ? config.fine_psd : 1.0, r_),
      use_slow_(config.sign_mode == SignMode::kSmooth && config.slow_jerk_psd > 0.0),
      use_fine_(config.sign_mode == SignMode::kSmooth && config.fine_psd > 0.0),
      use_cruise_(config.sign_mode == SignMode::kSmooth && config.cruise_window > 0.0) {
  if (!config.exact_covariance) build_gain_table();
  // The window's sums move every sample while armed: one division less each.
  if (use_cruise_) inv_cruise_window_ = 1.0 / config.cruise_window;
  still_time_ = config.still_time >= 0.0
                    ? config.still_time
                    : kRestTime * std::cbrt(config.quantum / kReferenceQuantum);
  reset();
}

double Differentiator::grid_dt(std::size_t k) const noexcept {
  if (k < kFine) return kFineStep * static_cast<double>(k + 1);
  return kFineEnd + static_cast<double>(k - kFine + 1) / coarse_inverse_step_;
}

void Differentiator::build_gain_table() {
  // Intervals past kFineEnd (only when max_gap exceeds it) share kCoarse steps.
  coarse_inverse_step_ = kCoarse / std::max(1e-9, cfg_.max_gap - kFineEnd);
  const std::size_t n = kFine + (cfg_.max_gap > kFineEnd ? kCoarse : 0);
  gains_.resize(n);
  gain_last_ = static_cast<double>(n - 1);
  // Each fixed point starts from the previous one: a few hundred steps each.
  const PolyKalman<3>::Mat* warm_v = nullptr;
  const PolyKalman<4>::Mat* warm_a = nullptr;
  const PolyKalman<3>::Mat* warm_s = nullptr;
  const PolyKalman<5>::Mat* warm_f = nullptr;
  PolyKalman<3>::Mat pv, ps;
  PolyKalman<4>::Mat pa;
  PolyKalman<5>::Mat pf;
  for (std::size_t k = 0; k < n; ++k) {
    const double dt = grid_dt(k);
    auto [kv, pv_k] = PolyKalman<3>::steady_state(cfg_.jerk_psd, r_, dt, warm_v);
    auto [ka, pa_k] = PolyKalman<4>::steady_state(cfg_.snap_psd, r_, dt, warm_a);
    auto [ks, ps_k] = use_slow_ ? PolyKalman<3>::steady_state(cfg_.slow_jerk_psd, r_, dt, warm_s)
                                : std::pair<PolyKalman<3>::Vec, PolyKalman<3>::Mat>{{}, {}};
    auto [kf, pf_k] = use_fine_ ? PolyKalman<5>::steady_state(cfg_.fine_psd, r_, dt, warm_f)
                                : std::pair<PolyKalman<5>::Vec, PolyKalman<5>::Mat>{{}, {}};
    pv = pv_k;
    pa = pa_k;
    ps = ps_k;
    pf = pf_k;
    warm_v = &pv;
    warm_a = &pa;
    warm_s = &ps;
    warm_f = &pf;
    const double sd = std::sqrt(pa[2][2]);
    GainRow& row = gains_[k].at;
    for (std::size_t i = 0; i < 3; ++i) {
      row[kGainPairs + 2 * i] = kv[i];
      row[kGainPairs + 2 * i + 1] = ks[i];
    }
    for (std::size_t i = 0; i < 4; ++i) {
      row[kGainAccFine + 2 * i] = ka[i];
      row[kGainAccFine + 2 * i + 1] = kf[i];
    }
    row[kGainFine4] = kf[4];
    row[kFineInvWidth] = use_fine_ ? 1.0 / (cfg_.smooth_sigmas * std::sqrt(pf[2][2])) : 0.0;
    row[kInvFineConsistency] = 1.0 / (cfg_.fine_consistency * sd);
    row[kSlowInvWidth] = use_slow_ ? 1.0 / (cfg_.slow_sigmas * std::sqrt(ps[2][2])) : 0.0;
    row[kInvConsistency] = 1.0 / (cfg_.slow_consistency * sd);
    row[kAccSd] = sd;
    row[kInvWidth] = 1.0 / (cfg_.smooth_sigmas * sd);
  }
  // The last node has no next one: a step of 0 keeps dt past it at its row.
  for (std::size_t k = 0; k < n; ++k) {
    const GainRow& next = gains_[std::min(k + 1, n - 1)].at;
    for (std::size_t i = 0; i < kGainFields; ++i)
      gains_[k].step[i] = next[i] - gains_[k].at[i];
  }
}

// Two doubles operated on together (an SSE2 register on x86-64; GCC and
// Clang lower it to scalar code on targets without one). The arithmetic is
// element-wise IEEE: each lane computes exactly what the scalar code would.
using Pair = double __attribute__((vector_size(16)));

inline Pair load_pair(const double* p) noexcept {
  Pair v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

inline void store_pair(double* p, Pair v) noexcept {
  std::memcpy(p, &v, sizeof v);
}

inline Pair splat(double v) noexcept {
  return Pair{v, v};
}

inline double Differentiator::gain_position(double dt) const noexcept {
  double pos;
  if (dt <= kFineEnd) {
    pos = dt * (1.0 / kFineStep) - 1.0;
  } else {
    pos = static_cast<double>(kFine) - 1.0 + (dt - kFineEnd) * coarse_inverse_step_;
  }
  return std::clamp(pos, 0.0, gain_last_);
}

Differentiator::GainRow Differentiator::gain_for(double dt) const noexcept {
  // Linear interpolation between the grid's neighbours of dt.
  const double pos = gain_position(dt);
  const auto k = static_cast<std::size_t>(pos);
  const double w = pos - static_cast<double>(k);
  const GainNode& node = gains_[k];
  GainRow g;
  for (std::size_t i = 0; i < kGainFields; ++i)
    g[i] = node.at[i] + w * node.step[i];
  return g;
}

Differentiator::SteadyGains Differentiator::steady_gains(double dt) const noexcept {
  SteadyGains out;
  if (gains_.empty() || !(dt > 0.0)) return out;
  const GainRow g = gain_for(dt);
  for (std::size_t i = 0; i < 3; ++i) {
    out.velocity[i] = g[kGainPairs + 2 * i];
    out.slow[i] = g[kGainPairs + 2 * i + 1];
  }
  for (std::size_t i = 0; i < 4; ++i) {
    out.acceleration[i] = g[kGainAccFine + 2 * i];
    out.fine[i] = g[kGainAccFine + 2 * i + 1];
  }
  out.fine[4] = g[kGainFine4];
  out.fine_inv_width = g[kFineInvWidth];
  out.inv_fine_consistency = g[kInvFineConsistency];
  out.acc_sd = g[kAccSd];
  out.inv_width = g[kInvWidth];
  out.slow_inv_width = g[kSlowInvWidth];
  out.inv_consistency = g[kInvConsistency];
  return out;
}

void Differentiator::enter_steady() noexcept {
  for (std::size_t i = 0; i < 3; ++i) {
    pair_state_[2 * i] = velocity_.state()[i];
    pair_state_[2 * i + 1] = slow_.state()[i];
  }
  for (std::size_t i = 0; i < 4; ++i) {
    acc_fine_state_[2 * i] = acceleration_.state()[i];
    acc_fine_state_[2 * i + 1] = fine_.state()[i];
  }
  fine_snap_ = fine_.state()[4];
  steady_ = true;
}

// gain_for() and PolyKalman::update_with_gain for the four channels at
// once, operation for operation (the same results, bit for bit;
// test_differentiator.cpp pins it), written for the processor rather than
// per channel: F(dt) is formed once, the velocity and slow channels (the
// same F) run side by side as Pairs, as do the acceleration and fine
// channels (the fine one's fifth state added to its lane alone) and the
// interpolation of the gains; nothing goes through memory but the state.
inline Differentiator::Step Differentiator::steady_step(double dt, double z) noexcept {
  // The interval's gains (gain_for()): node + w (next node - node).
  const double pos = gain_position(dt);
  // pos is in [0, gains_.size() - 1]: the int conversion is exact and cheaper.
  const int k = static_cast<int>(pos);
  const Pair w = splat(pos - static_cast<double>(k));
  const GainNode& node = gains_[static_cast<std::size_t>(k)];
  const auto gain = [&](std::size_t i) {
    return load_pair(&node.at[i]) + w * load_pair(&node.step[i]);
  };
  // PolyKalman's taylor(): c[k] = c[k - 1] dt / k; its predicted() sums
  // from 0.0, the first term times c[0] = 1.
  const double c1 = dt;
  const double c2 = c1 * dt * 0.5;
  const double c3 = c2 * dt * (1.0 / 3.0);
  const double c4 = c3 * dt * 0.25;
  const Pair zero = splat(0.0), c1s = splat(c1), c2s = splat(c2), c3s = splat(c3), zs = splat(z);

  // Velocity and slow channel: {velocity[i], slow[i]}.
  const Pair s0 = load_pair(&pair_state_[0]), s1 = load_pair(&pair_state_[2]),
             s2 = load_pair(&pair_state_[4]);
  const Pair p0 = zero + s0 + c1s * s1 + c2s * s2;
  const Pair p1 = zero + s1 + c1s * s2;
  const Pair p2 = zero + s2;
  const Pair innovation = zs - p0;
  store_pair(&pair_state_[0], p0 + gain(kGainPairs) * innovation);
  store_pair(&pair_state_[2], p1 + gain(kGainPairs + 2) * innovation);
  store_pair(&pair_state_[4], p2 + gain(kGainPairs + 4) * innovation);

  // Acceleration and fine channel: {acceleration[i], fine[i]}, i < 4; the
  // fine channel's fifth state (f4) has no counterpart: its terms are added
  // to lane 1 alone, last, where its place in the sum is.
  const Pair a0 = load_pair(&acc_fine_state_[0]), a1 = load_pair(&acc_fine_state_[2]),
             a2 = load_pair(&acc_fine_state_[4]), a3 = load_pair(&acc_fine_state_[6]);
  const double f4 = fine_snap_;
  Pair q0 = zero + a0 + c1s * a1 + c2s * a2 + c3s * a3;
  q0[1] += c4 * f4;
  Pair q1 = zero + a1 + c1s * a2 + c2s * a3;
  q1[1] += c3 * f4;
  Pair q2 = zero + a2 + c1s * a3;
  q2[1] += c2 * f4;
  Pair q3 = zero + a3;
  q3[1] += c1 * f4;
  const double q4 = 0.0 + f4;
  const Pair innovations = zs - q0;
  const Pair gain0 = gain(kGainAccFine);
  store_pair(&acc_fine_state_[0], q0 + gain0 * innovations);
  store_pair(&acc_fine_state_[2], q1 + gain(kGainAccFine + 2) * innovations);
  const Pair xdd = q2 + gain(kGainAccFine + 4) * innovations;
  store_pair(&acc_fine_state_[4], xdd);
  store_pair(&acc_fine_state_[6], q3 + gain(kGainAccFine + 6) * innovations);
  const Pair fine4_width = gain(kGainFine4);
  fine_snap_ = q4 + fine4_width[0] * innovations[1];

  const Pair slow_consistency = gain(kSlowInvWidth), sd_width = gain(kAccSd),
             fine_consistency = gain(kInvFineConsistency);
  Step step;
  step.x = pair_state_[0];
  step.xd = pair_state_[2];
  step.xdd = xdd[0];
  step.fine_xdd = xdd[1];
  step.slow_xdd = pair_state_[5];
  step.acc_sd = sd_width[0];
  step.inv_width = sd_width[1];
  step.slow_inv_width = slow_consistency[0];
  step.inv_consistency = slow_consistency[1];
  step.fine_inv_width = fine4_width[1];
  step.inv_fine_consistency = fine_consistency[0];
  step.acc_innovation = innovations[0];
  step.acc_gain0 = gain0[0];
  return step;
}

void Differentiator::reset() noexcept {
  started_ = false;
  out_ = {};
}

void Differentiator::start(double t, double x) noexcept {
  started_ = true;
  restarted_ = true;
  t_ = t;
  // Prior spread of the rates at start: generous for a hand or a motor
  // (rad/s, rad/s^2, rad/s^3), so the first samples dominate.
  velocity_.start(x, {0.0, 10.0, 100.0});
  acceleration_.start(x, {0.0, 10.0, 100.0, 1000.0});
  slow_.start(x, {0.0, 10.0, 100.0});
  fine_.start(x, {0.0, 10.0, 100.0, 1000.0, 10000.0});
  in_band_ = 0.0;
  last_x_ = x;
  still_ = 0.0;
  settling_ = kSettlingSamples;
  steady_ = false;
  // Nothing seen yet that the acceleration channel could not follow.
  window_head_ = 0;
  window_size_ = 1;
  window_t_[0] = t;
  window_x_[0] = x;
  nis_ = 1.0;
  since_inconsistent_ = std::numeric_limits<double>::infinity();
  moments_valid_ = false;
  out_ = {x, 0.0, 0.0, 0.0, 0.0, true};
}

inline double Differentiator::decide_sign(const Step& step, double dt) noexcept {
  // Correction (rest, corrections.hpp): assumes a joint whose encoder has
  // not changed for still_time has stopped. At rest the true acceleration
  // is exactly 0 and the model's state must not move; the acceleration
  // estimate still rings for a while after a stop (the jerk ends abruptly),
  // so an encoder that has not moved decides.
  if (still_time_ > 0.0 && still_ >= still_time_) {
    in_band_ = 0.0;
    return 0.0;
  }
  if (cfg_.sign_mode != SignMode::kHard) {
    // The expected sign across the estimate's uncertainty, as a ramp: no
    // decision delay at a zero crossing and no chatter. The model is linear
    // in sgn(xdd), so a fraction acts as the expected value of both branches.
    double xdd = step.xdd;
    double sign = std::clamp(xdd * step.inv_width, -1.0, 1.0);
    if (use_fine_) {
      // Where the fast estimate agrees with the fine channel's (within the
      // fast one's noise), the motion is as smooth as the fine channel's
      // model and its finer estimate decides; where they disagree (a
      // manoeuvre, which the smoother model follows late) the fast one does.
      // The blended acceleration is what the slow channel is then held against.
      const double d = std::min(1.0, std::fabs(xdd - step.fine_xdd) * step.inv_fine_consistency);
      const double fine = std::clamp(step.fine_xdd * step.fine_inv_width, -1.0, 1.0);
      sign = d * d * sign + (1.0 - d * d) * fine;
      xdd = d * d * xdd + (1.0 - d * d) * step.fine_xdd;
    }
    if (use_slow_) {
      // Where the fast estimate agrees with the slow channel's (within its own
      // noise), the motion's acceleration varies slowly and the slow channel,
      // with a fraction of the noise, tells its sign: in creeping motion the
      // fast channel's noise alone would flip eq. (4)'s drive at random.
      // Where they disagree (a reversal, a stop) the slow one lags: fast decides.
      const double d = std::min(1.0, std::fabs(xdd - step.slow_xdd) * step.inv_consistency);
      const double slow = std::clamp(step.slow_xdd * step.slow_inv_width, -1.0, 1.0);
      sign = d * d * sign + (1.0 - d * d) * slow;
    }
    // Correction (cruise, corrections.hpp): assumes a stroke after a
    // reversal runs at constant speed. After a manoeuvre the acceleration
    // channel could not follow, the motion is not the smooth kind its model
    // describes: it may be a stroke at constant speed, where the true xdd is
    // exactly 0 (and the channel rings for 0.1-0.2 s). The expected sign is
    // then (1 - P(cruise)) times the sign given motion. On smooth motion the
    // channel stays consistent and this never runs: its small accelerations
    // keep their sign.
    if (use_cruise_ && since_inconsistent_ < cfg_.cruise_armed_time)
      sign *= 1.0 - cruise_probability();
    return sign;
  }
  // Hard: a dead band with hysteresis around zero, scaled by the estimate's
  // own uncertainty; a decided sign is held inside the release band for
  // sign_hold (through the end of a deceleration), then 0.
  const bool fixed = cfg_.acc_sign_threshold >= 0.0;
  const double xdd = step.xdd;
  const double on = fixed ? cfg_.acc_sign_threshold : cfg_.sign_sigmas * step.acc_sd;
  const double off = fixed ? cfg_.acc_sign_threshold : cfg_.sign_release * step.acc_sd;
  double sign = out_.acc_sign;
  if (sign * xdd < off) {
    in_band_ += dt;
    if (in_band_ > cfg_.sign_hold) sign = 0.0;
  } else {
    in_band_ = 0.0;
  }
  if (xdd > on) sign = 1.0, in_band_ = 0.0;
  if (xdd < -on) sign = -1.0, in_band_ = 0.0;
  return sign;
}

void Differentiator::track_consistency(double t, double x, double innovation, double innovation_var,
                                       double dt) noexcept {
  // A Kalman filter whose model holds has innovations of its predicted
  // variance: their normalised square averages 1 (on smooth motion, 1 +- 0.5
  // over 5 ms, at most about 5 on every multisine tried). A manoeuvre whose
  // jerk jumps (a reversal's start and end) takes it to hundreds.
  const double w = std::min(1.0, dt / kNisTime);
  nis_ += w * (innovation * innovation / innovation_var - nis_);
  since_inconsistent_ = nis_ > cfg_.cruise_nis ? 0.0 : since_inconsistent_ + dt;
  const double dx = x - window_x_[window_head_];
  window_head_ = (window_head_ + 1) % kWindowCapacity;
  window_t_[window_head_] = t;
  window_x_[window_head_] = x;
  window_size_ = std::min(window_size_ + 1, kWindowCapacity);
  if (since_inconsistent_ >= cfg_.cruise_armed_time) {
    moments_valid_ = false;  // not needed until the next manoeuvre
  } else if (!moments_valid_ || ++since_rebuild_ >= kRebuildSamples) {
    rebuild_moments();
  } else {
    advance_moments(dt, dx);
  }
}

// The window's fit works on the power sums M_k = sum u^k (k <= 6) and
// B_k = sum u^k y (k <= 3) over its samples, u = (t_i - t) / cruise_window
// in [-1, 0] and y = x_i - x about the newest sample (well conditioned).
inline void Differentiator::add_to_moments(double u, double y, double weight) noexcept {
  const double u2 = u * u, u3 = u2 * u;
  moments_[0] += weight;
  moments_[1] += weight * u;
  moments_[2] += weight * u2;
  moments_[3] += weight * u3;
  moments_[4] += weight * u2 * u2;
  moments_[5] += weight * u2 * u3;
  moments_[6] += weight * u3 * u3;
  const double wy = weight * y;
  moments_y_[0] += wy;
  moments_y_[1] += wy * u;
  moments_y_[2] += wy * u2;
  moments_y_[3] += wy * u3;
}

void Differentiator::rebuild_moments() noexcept {
  const double inv_window = 1.0 / cfg_.cruise_window;
  const double t_now = window_t_[window_head_];
  const double x_now = window_x_[window_head_];
  moments_ = {};
  moments_y_ = {};
  // At most capacity - 1 samples (see advance_moments): above about 3 kHz
  // the window is the newest 127 samples.
  const std::size_t most = std::min(window_size_, kWindowCapacity - 1);
  std::size_t n = 0;
  for (; n < most; ++n) {
    const std::size_t i = (window_head_ + kWindowCapacity - n) % kWindowCapacity;
    const double u = (window_t_[i] - t_now) * inv_window;
    if (u < -1.0) break;
    add_to_moments(u, window_x_[i] - x_now, 1.0);
  }
  window_count_ = n;
  since_rebuild_ = 0;
  moments_valid_ = true;
}

void Differentiator::advance_moments(double dt, double dx) noexcept {
  // The same sums, moved to the new newest sample in O(1): every y drops by
  // dx, every u by dt / window ((u + d)^k by the binomial theorem, highest
  // k first so that the lower sums are still the old ones); then the new
  // sample (u = 0, y = 0) joins and those now older than the window leave.
  // Rounding accumulates in the sums, so they are rebuilt from the samples
  // every kRebuildSamples.
  static constexpr double kBinomial[7][7] = {{1, 0, 0, 0, 0, 0, 0},   {1, 1, 0, 0, 0, 0, 0},
                                             {1, 2, 1, 0, 0, 0, 0},   {1, 3, 3, 1, 0, 0, 0},
                                             {1, 4, 6, 4, 1, 0, 0},   {1, 5, 10, 10, 5, 1, 0},
                                             {1, 6, 15, 20, 15, 6, 1}};
  for (std::size_t k = 0; k < 4; ++k)
    moments_y_[k] -= dx * moments_[k];
  const double d = -dt * inv_cruise_window_;
  double p[7];
  p[0] = 1.0;
  for (std::size_t i = 1; i < 7; ++i)
    p[i] = p[i - 1] * d;
  for (std::size_t k = 6; k >= 1; --k) {
    double v = 0.0;
    for (std::size_t j = 0; j <= k; ++j)
      v += kBinomial[k][j] * p[k - j] * moments_[j];
    moments_[k] = v;
  }
  for (std::size_t k = 3; k >= 1; --k) {
    double v = 0.0;
    for (std::size_t j = 0; j <= k; ++j)
      v += kBinomial[k][j] * p[k - j] * moments_y_[j];
    moments_y_[k] = v;
  }
  moments_[0] += 1.0;
  ++window_count_;
  const double inv_window = inv_cruise_window_;
  const double t_now = window_t_[window_head_];
  const double x_now = window_x_[window_head_];
  // The ring must keep every sample of the window: at most capacity - 1, so
  // that the next sample does not overwrite the oldest one still in it.
  while (window_count_ > 0) {
    const std::size_t i = (window_head_ + kWindowCapacity - (window_count_ - 1)) % kWindowCapacity;
    const double u = (window_t_[i] - t_now) * inv_window;
    if (u >= -1.0 && window_count_ < kWindowCapacity) break;
    add_to_moments(u, window_x_[i] - x_now, -1.0);
    --window_count_;
  }
}

double Differentiator::cruise_probability() const noexcept {
  // Least-squares cubic c0 + c1 u + c2 u^2 + c3 u^3 through the samples of the
  // last cruise_window, on their actual time stamps (the sums above). A
  // finite window forgets a manoeuvre entirely once it has passed, where the
  // Kalman channels ring.
  const double window = cfg_.cruise_window;
  const auto& m = moments_;
  const auto& b = moments_y_;
  const std::size_t n = window_count_;
  if (n < kMinWindowSamples) return 0.0;
  // Only c2, c3 and their covariance are needed: with the normal matrix in
  // 2x2 blocks [A B; B' D], they come from the Schur complement
  // S = D - B' A^-1 B: (c2, c3) = S^-1 ((b2, b3) - B' A^-1 (b0, b1)), and
  // their covariance is r S^-1.
  const double det_a = m[0] * m[2] - m[1] * m[1];
  if (!(det_a > 0.0)) return 0.0;
  // A^-1 B, column by column (A^-1 = [m2 -m1; -m1 m0] / det_a).
  const double inv_a = 1.0 / det_a;
  const double k00 = (m[2] * m[2] - m[1] * m[3]) * inv_a, k10 = (m[0] * m[3] - m[1] * m[2]) * inv_a;
  const double k01 = (m[2] * m[3] - m[1] * m[4]) * inv_a, k11 = (m[0] * m[4] - m[1] * m[3]) * inv_a;
  const double s00 = m[4] - (m[2] * k00 + m[3] * k10);
  const double s01 = m[5] - (m[2] * k01 + m[3] * k11);
  const double s11 = m[6] - (m[3] * k01 + m[4] * k11);
  const double r2 = b[2] - (k00 * b[0] + k10 * b[1]);
  const double r3 = b[3] - (k01 * b[0] + k11 * b[1]);
  const double det_s = s00 * s11 - s01 * s01;
  if (!(det_s > 0.0)) return 0.0;
  const double inv_s = 1.0 / det_s;
  const double i00 = s11 * inv_s, i01 = -s01 * inv_s, i11 = s00 * inv_s;  // S^-1
  const double c2 = i00 * r2 + i01 * r3, c3 = i01 * r2 + i11 * r3;
  // Acceleration and jerk at the newest sample, and their covariance.
  const double w2 = 1.0 / (window * window), w3 = w2 / window;
  const double acc = 2.0 * c2 * w2, jerk = 6.0 * c3 * w3;
  const double r = r_ * cfg_.cruise_noise;
  const double caa = r * 4.0 * i00 * w2 * w2;
  const double caj = r * 12.0 * i01 * w2 * w3;
  const double cjj = r * 36.0 * i11 * w3 * w3;
  // Bayes factor of "acceleration and jerk exactly 0" against "Gaussian with
  // the spread of a moving hand": N(e; 0, C) / N(e; 0, C + Pr).
  const double det0 = caa * cjj - caj * caj;
  const double paa = caa + kMovingAccSd * kMovingAccSd, pjj = cjj + kMovingJerkSd * kMovingJerkSd;
  const double det1 = paa * pjj - caj * caj;
  if (!(det0 > 0.0) || !(det1 > 0.0)) return 0.0;
  const double q0 = (cjj * acc * acc - 2.0 * caj * acc * jerk + caa * jerk * jerk) / det0;
  const double q1 = (pjj * acc * acc - 2.0 * caj * acc * jerk + paa * jerk * jerk) / det1;
  // P = odds / (1 + odds) with odds = prior odds x exp(-(q0 - q1) / 2)
  // sqrt(det1 / det0), written as 1 / (1 + 1 / odds): no logarithm, and an
  // exp() that overflows gives P = 0 and one that underflows P = 1.
  const double inverse_odds = (1.0 - cfg_.cruise_prior) / cfg_.cruise_prior *
                              std::exp(0.5 * (q0 - q1)) * std::sqrt(det0 / det1);
  return 1.0 / (1.0 + inverse_odds);
}

Derivatives Differentiator::update(double t, double x) noexcept {
  if (!std::isfinite(t) || !std::isfinite(x)) return invalidated(out_);
  if (!started_) {
    start(t, x);
    return out_;
  }
  const double dt = t - t_;
  if (!(dt > 0.0)) return invalidated(out_);
  if (dt > cfg_.max_gap) {
    start(t, x);
    return out_;
  }
  restarted_ = false;
  t_ = t;
  Step step;
  if (cfg_.exact_covariance || settling_ > 0) {
    step = full_step(dt, x);
  } else {
    if (!steady_) enter_steady();
    // Without the slow or fine channel its gains are 0: its lane runs idle.
    step = steady_step(dt, x);
  }
  // The acceleration channel's innovation against its predicted variance,
  // P[0][0] + r = r / (1 - K[0]): the cruise hypothesis' consistency test.
  if (use_cruise_) track_consistency(t, x, step.acc_innovation, r_ / (1.0 - step.acc_gain0), dt);
  still_ = x == last_x_ ? still_ + dt : 0.0;
  last_x_ = x;
  const double sign = decide_sign(step, dt);
  // out_ written in 16-byte pairs from registers, the way it is copied to
  // the result: field by field, GCC merged the copy into 16-byte loads of
  // two 8-byte stores, which the processor cannot forward (a stall on the
  // way from the sample to the model).
  auto* bytes = reinterpret_cast<unsigned char*>(&out_);
  const Pair position = {step.x, step.xd}, acceleration = {step.xdd, sign};
  std::memcpy(bytes + offsetof(Derivatives, x), &position, sizeof position);
  std::memcpy(bytes + offsetof(Derivatives, xdd), &acceleration, sizeof acceleration);
  out_.acc_sd = step.acc_sd;
  out_.valid = true;
  return out_;
}

// Out of line: the hot steady-state path of update() then needs no stack
// frame for the covariance recursion's temporaries.
[[gnu::noinline]] Differentiator::Step Differentiator::full_step(double dt, double x) noexcept {
  // The full recursion: always, or while the filters settle from their
  // start-up prior (the steady-state gains would converge more slowly).
  if (settling_ > 0) --settling_;
  Step step;
  step.acc_innovation = x - acceleration_.predicted(dt)[0];
  velocity_.update(dt, x);
  acceleration_.update(dt, x);
  // After a correction P[0][0] = K[0] r.
  step.acc_gain0 = acceleration_.covariance()[0][0] / r_;
  step.acc_sd = std::sqrt(acceleration_.covariance()[2][2]);
  step.inv_width = 1.0 / (cfg_.smooth_sigmas * step.acc_sd);
  if (use_slow_) slow_.update(dt, x);
  if (use_fine_) fine_.update(dt, x);
  step.fine_xdd = fine_.state()[2];
  step.fine_inv_width =
      use_fine_ ? 1.0 / (cfg_.smooth_sigmas * std::sqrt(fine_.covariance()[2][2])) : 0.0;
  step.inv_fine_consistency = 1.0 / (cfg_.fine_consistency * step.acc_sd);
  step.slow_inv_width =
      use_slow_ ? 1.0 / (cfg_.slow_sigmas * std::sqrt(slow_.covariance()[2][2])) : 0.0;
  step.inv_consistency = 1.0 / (cfg_.slow_consistency * step.acc_sd);
  step.x = velocity_.state()[0];
  step.xd = velocity_.state()[1];
  step.xdd = acceleration_.state()[2];
  step.slow_xdd = slow_.state()[2];
  return step;
}

}  // namespace tsmh::estimator
