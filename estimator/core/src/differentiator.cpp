#include "estimator/differentiator.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>

namespace tsmh::estimator {
namespace {

constexpr double kFineStep = 25e-6;  // s, grid step up to kFineEnd
constexpr std::size_t kFine = 160;   // 25 us ... 4 ms
constexpr double kFineEnd = kFineStep * kFine;
constexpr std::size_t kCoarse = 200;  // kFineEnd ... max_gap
// Samples of full recursion after a (re)start, while the covariance falls
// from the start-up prior to its steady state (about 0.1 s at 1 kHz).
constexpr int kSettlingSamples = 100;
double noise_variance(const DifferentiatorConfig& c) {
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
      r_(noise_variance(config)),
      velocity_(config.jerk_psd, r_),
      acceleration_(config.snap_psd, r_),
      slow_(config.slow_jerk_psd > 0.0 ? config.slow_jerk_psd : 1.0, r_),
      fine_(config.fine_psd > 0.0 ? config.fine_psd : 1.0, r_),
      use_slow_(config.sign_mode == SignMode::kSmooth && config.slow_jerk_psd > 0.0),
      use_fine_(config.sign_mode == SignMode::kSmooth && config.fine_psd > 0.0) {
  if (!config.exact_covariance) build_gain_table();
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
  settling_ = kSettlingSamples;
  steady_ = false;
  acc_innovation_ = acc_gain0_ = 0.0;
  out_ = {x, 0.0, 0.0, 0.0, 0.0, true};
}

inline double Differentiator::decide_sign(const Step& step, double dt) noexcept {
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
  acc_innovation_ = step.acc_innovation;
  acc_gain0_ = step.acc_gain0;
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
