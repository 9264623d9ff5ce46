#include "estimator/corrections.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace tsmh::estimator {
namespace {

// Cruise: the acceleration channel's normalised innovation squared is
// averaged over this time (s) before it is held against cruise_nis; fewer
// samples than kMinWindowSamples in the window: no test.
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

}  // namespace

RestCorrection::RestCorrection(double still_time, double quantum) noexcept
    : still_time_(still_time >= 0.0 ? still_time
                                    : kRestTime * std::cbrt(quantum / kReferenceQuantum)),
      enabled_(still_time_ > 0.0) {
  if (!enabled_) still_time_ = std::numeric_limits<double>::infinity();
}

CruiseCorrection::CruiseCorrection(const CorrectionsConfig& config, double measurement_variance,
                                   bool enabled)
    : enabled_(enabled && config.cruise_window > 0.0),
      window_(config.cruise_window),
      inv_window_(enabled_ ? 1.0 / config.cruise_window : 0.0),
      prior_(config.cruise_prior),
      nis_limit_(config.cruise_nis),
      armed_time_(config.cruise_armed_time),
      r_(measurement_variance * config.cruise_noise) {}

void CruiseCorrection::restart(double t, double x) noexcept {
  head_ = 0;
  size_ = 1;
  window_t_[0] = t;
  window_x_[0] = x;
  nis_ = 1.0;
  since_inconsistent_ = std::numeric_limits<double>::infinity();
  moments_valid_ = false;
}

void CruiseCorrection::observe(double t, double x, double innovation, double innovation_var,
                               double dt) noexcept {
  // A Kalman filter whose model holds has innovations of its predicted
  // variance: their normalised square averages 1 (on smooth motion, 1 +- 0.5
  // over 5 ms, at most about 5 on every multisine tried). A manoeuvre whose
  // jerk jumps (a reversal's start and end) takes it to hundreds.
  const double w = std::min(1.0, dt / kNisTime);
  nis_ += w * (innovation * innovation / innovation_var - nis_);
  since_inconsistent_ = nis_ > nis_limit_ ? 0.0 : since_inconsistent_ + dt;
  const double dx = x - window_x_[head_];
  head_ = (head_ + 1) % kCapacity;
  window_t_[head_] = t;
  window_x_[head_] = x;
  size_ = std::min(size_ + 1, kCapacity);
  if (since_inconsistent_ >= armed_time_) {
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
inline void CruiseCorrection::add_to_moments(double u, double y, double weight) noexcept {
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

void CruiseCorrection::rebuild_moments() noexcept {
  const double inv_window = inv_window_;
  const double t_now = window_t_[head_];
  const double x_now = window_x_[head_];
  moments_ = {};
  moments_y_ = {};
  // At most capacity - 1 samples (see advance_moments): above about 3 kHz
  // the window is the newest 127 samples.
  const std::size_t most = std::min(size_, kCapacity - 1);
  std::size_t n = 0;
  for (; n < most; ++n) {
    const std::size_t i = (head_ + kCapacity - n) % kCapacity;
    const double u = (window_t_[i] - t_now) * inv_window;
    if (u < -1.0) break;
    add_to_moments(u, window_x_[i] - x_now, 1.0);
  }
  count_ = n;
  since_rebuild_ = 0;
  moments_valid_ = true;
}

void CruiseCorrection::advance_moments(double dt, double dx) noexcept {
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
  const double d = -dt * inv_window_;
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
  ++count_;
  const double inv_window = inv_window_;
  const double t_now = window_t_[head_];
  const double x_now = window_x_[head_];
  // The ring must keep every sample of the window: at most capacity - 1, so
  // that the next sample does not overwrite the oldest one still in it.
  while (count_ > 0) {
    const std::size_t i = (head_ + kCapacity - (count_ - 1)) % kCapacity;
    const double u = (window_t_[i] - t_now) * inv_window;
    if (u >= -1.0 && count_ < kCapacity) break;
    add_to_moments(u, window_x_[i] - x_now, -1.0);
    --count_;
  }
}

double CruiseCorrection::probability() const noexcept {
  // Least-squares cubic c0 + c1 u + c2 u^2 + c3 u^3 through the samples of the
  // last cruise_window, on their actual time stamps (the sums above). A
  // finite window forgets a manoeuvre entirely once it has passed, where the
  // Kalman channels ring.
  const double window = window_;
  const auto& m = moments_;
  const auto& b = moments_y_;
  const std::size_t n = count_;
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
  const double r = r_;
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
  const double inverse_odds =
      (1.0 - prior_) / prior_ * std::exp(0.5 * (q0 - q1)) * std::sqrt(det0 / det1);
  return 1.0 / (1.0 + inverse_odds);
}

CorrectedDifferentiator::CorrectedDifferentiator(const DifferentiatorConfig& diff,
                                                 const CorrectionsConfig& corrections)
    : cfg_(corrections),
      filter_(diff),
      rest_(corrections.still_time, diff.quantum),
      cruise_(corrections, filter_.measurement_variance(), diff.sign_mode == SignMode::kSmooth) {}

HindsightCorrection::HindsightCorrection(const HindsightConfig& config, bool enabled)
    : cfg_(config), enabled_(enabled && config.lag > 0.0) {
  // certain <= sure: a step at `sure` (the weight is 1 beyond it).
  const auto inverse_span = [](double sure, double certain) {
    return certain > sure ? 1.0 / (certain - sure) : std::numeric_limits<double>::infinity();
  };
  inv_span_ = inverse_span(config.sure, config.certain);
  inv_span_armed_ = inverse_span(config.sure_armed, config.certain_armed);
}

// A correction from sample j on (after_step() found it; the samples before
// it needed none): j is stepped again from the state before it, and when
// that changes its friction, every later sample too, to now. After a
// correction the samples up to `ahead` younger are looked at in the same
// pass, so that one pass to now serves them all. Out of line: rare.
[[gnu::noinline]] double HindsightCorrection::correct(std::size_t j, const Verdict& first,
                                                      const CorrectedDifferentiator& diff,
                                                      FrictionDynamics& model) noexcept {
  const double t = history_[newest_].m.t;
  const Seen now = seen(diff);
  model.save_state(now_);  // the newest state, should nothing change
  bool dirty = false;      // the samples after `frontier` are to be stepped again
  std::size_t frontier = j;
  Verdict v = first;
  while (true) {
    if (v.corrected || dirty) {
      // While dirty, every sample is stepped again from the corrected path.
      Motion m = history_[j].m;
      if (v.rest) {
        m.xd = m.xdd = m.acc_sign = 0.0;
      } else if (v.corrected) {
        m.acc_sign = v.sign;
      }
      dirty = step_again(j, m, dirty, model) || dirty;
      frontier = j;
    }
    if (pending_ == 0) break;
    j = index_back(pending_ - 1);
    const double back = t - history_[j].m.t;
    if (back < cfg_.lag && pending_ < kMaxPending && !(dirty && back >= cfg_.lag - cfg_.ahead))
      break;
    --pending_;
    v = judge(history_[j], back, now, diff);
  }
  if (dirty) {
    catch_up(frontier, model);  // the model ends at the newest sample
  } else {
    model.restore_state(now_);
  }
  return history_[newest_].friction;
}

// Steps sample j again with the motion m from the state before it (on the
// corrected path when `dirty`, which the model then holds already): true
// when that changed its friction, so that the samples after it must be
// stepped again. Out of line: rare, and the per-sample decision above stays
// compact.
[[gnu::noinline]] bool HindsightCorrection::step_again(std::size_t j, const Motion& m, bool dirty,
                                                       FrictionDynamics& model) noexcept {
  Sample& s = history_[j];
  const std::size_t before = (j + kHistory - 1) % kHistory;
  if (!dirty) {
    // The state before j: the checkpoint at or before it, and the samples
    // since stepped again as they were.
    const std::size_t from = before - before % kStride;
    model.restore_state(checkpoints_[from / kStride]);
    for (std::size_t k = from + 1; k <= before; ++k)
      model.step(history_[k].m, history_[k].m.t - history_[k - 1].m.t);
  }
  // The interval as the estimator formed it: this sample's time less the last one's.
  const double f = model.step(m, m.t - history_[before].m.t);
  const double level = model.sliding_friction();
  const double tolerance = 1e-4 * (std::isfinite(level) ? std::max(level, 1.0) : 1.0);
  const bool changed = std::fabs(f - s.friction) > tolerance;
  // A correction too small to matter on the uncorrected path is dropped.
  if (!changed && !dirty) return false;
  s.m = m;
  s.friction = f;
  if (j % kStride == 0) model.save_state(checkpoints_[j / kStride]);
  ++resteps_;
  return changed;
}

// Steps every sample after `from` to the newest again, from the state the
// model holds (from's): the model then holds the corrected newest state.
[[gnu::noinline]] void HindsightCorrection::catch_up(std::size_t from,
                                                     FrictionDynamics& model) noexcept {
  for (std::size_t k = (from + 1) % kHistory; k != (newest_ + 1) % kHistory;
       k = (k + 1) % kHistory) {
    Sample& later = history_[k];
    const double t_before = history_[(k + kHistory - 1) % kHistory].m.t;
    later.friction = model.step(later.m, later.m.t - t_before);
    if (k % kStride == 0) model.save_state(checkpoints_[k / kStride]);
    ++resteps_;
  }
}

}  // namespace tsmh::estimator
