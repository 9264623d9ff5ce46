#include "haptics/recalibration.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "estimator/contact_check.hpp"
#include "realtime/enum_names.hpp"

namespace tsmh::haptics {
namespace {

constexpr double kSlidingSpeed = 0.1;  // rad/s: below it the joint is reversing or at rest

}  // namespace

std::string_view to_string(CalibrationState s) noexcept {
  return realtime::enum_name<CalibrationState::kRefused>(
      s, {"idle", "collecting", "identifying", "applied", "refused"});
}

std::string_view to_string(CalibrationReason r) noexcept {
  return realtime::enum_name<CalibrationReason::kNoData>(
      r, {"none", "motion too small", "not free motion (contact)", "new model not better",
          "implausible scale", "no slave data"});
}

Recalibration::Recalibration(int joints, const RecalibrationConfig& config,
                             const DriftConfig& drift,
                             std::vector<std::unique_ptr<estimator::FrictionModel>> replicas)
    : joints_(joints), config_(config), replicas_(std::move(replicas)) {
  if (joints < 1 || joints > static_cast<int>(kMaxJoints))
    throw std::invalid_argument("recalibration: joints must be 1..kMaxJoints");
  if (!(config.collect_s > 0.0) || config.capacity < 100 || !(config.ramp_per_s > 0.0) ||
      !(config.min_scale > 0.0) || !(config.max_scale > config.min_scale))
    throw std::invalid_argument("recalibration: inconsistent configuration");
  for (std::size_t j = 0; j < kMaxJoints; ++j) {
    drift_[j] = DriftMonitor(drift);
    for (int d = 0; d < 2; ++d) {
      applied_[j][d] = 1.0;
      target_[j][d].store(1.0, std::memory_order_relaxed);
    }
    drift_scale_[j].store(std::nan(""), std::memory_order_relaxed);
    if (static_cast<int>(j) < joints) buffer_[j].resize(config.capacity);
    level_mode_[j] = config.scale == RecalibrationScale::kLevels && j < replicas_.size() &&
                     replicas_[j] && replicas_[j]->set_level_scale(1.0);
  }
}

void Recalibration::request(std::uint32_t mask) noexcept {
  const std::uint32_t valid = joints_ >= 32 ? ~0U : (1U << joints_) - 1U;
  if ((mask & valid) != 0) requested_.fetch_or(mask & valid, std::memory_order_relaxed);
}

void Recalibration::on_estimate(int joint, double t, double x_in, estimator::Estimate& e,
                                double radius_m) noexcept {
  const std::size_t j = idx(joint);
  if (!e.valid) return;
  radius_[j] = radius_m;
  const double raw = e.friction;
  // kOutput: one scale for both directions, on the model's output; kLevels:
  // the model already ran at the applied scales, the estimate stays.
  if (!level_mode_[j]) {
    e.friction = applied_[j][0] * raw;
    e.friction_level = applied_[j][0] * e.friction_level;
    e.tau_out_est = e.tau_in - radius_m * e.friction;
  }
  drift_[j].update(t, e, radius_m);
  drift_scale_[j].store(
      drift_[j].judged() ? drift_[j].scale() * applied_scale(joint) : std::nan(""),
      std::memory_order_relaxed);
  const std::uint32_t bit = 1U << j;
  const std::uint32_t mask = drift_mask_.load(std::memory_order_relaxed);
  const std::uint32_t now = drift_[j].alarm() ? (mask | bit) : (mask & ~bit);
  if (now != mask) drift_mask_.store(now, std::memory_order_relaxed);

  if (phase_.load(std::memory_order_relaxed) ==
          static_cast<std::int32_t>(CalibrationState::kCollecting) &&
      (mask_.load(std::memory_order_relaxed) & bit) != 0 && count_[j] < buffer_[j].size())
    buffer_[j][count_[j]++] =
        Sample{t, x_in, e.xd, e.xdd, e.acc_sign, e.tau_in, e.tension, radius_m * raw};
}

void Recalibration::on_tick(double now_s, double dt, bool button) noexcept {
  const auto phase = static_cast<CalibrationState>(phase_.load(std::memory_order_acquire));
  // A new result from the worker: ramp towards it, restart drift watching.
  const std::uint64_t results = results_.load(std::memory_order_acquire);
  if (results != results_seen_) {
    results_seen_ = results;
    if (phase == CalibrationState::kApplied)
      for (int j = 0; j < joints_; ++j)
        if ((mask_.load(std::memory_order_relaxed) >> j) & 1U) drift_[idx(j)].reset();
  }
  // Requests: the button's press (edge), or any thread's request().
  std::uint32_t want = requested_.exchange(0, std::memory_order_relaxed);
  if (button && !button_was_) want |= joints_ >= 32 ? ~0U : (1U << joints_) - 1U;
  button_was_ = button;
  const bool busy =
      phase == CalibrationState::kCollecting || phase == CalibrationState::kIdentifying;
  if (want != 0 && !busy) {
    for (int j = 0; j < joints_; ++j)
      count_[idx(j)] = 0;
    mask_.store(want, std::memory_order_relaxed);
    reason_.store(0, std::memory_order_relaxed);
    reason_joint_.store(-1, std::memory_order_relaxed);
    collect_start_s_ = now_s;
    phase_.store(static_cast<std::int32_t>(CalibrationState::kCollecting),
                 std::memory_order_relaxed);
  } else if (phase == CalibrationState::kCollecting) {
    bool full = false;
    for (int j = 0; j < joints_; ++j)
      full = full || count_[idx(j)] >= buffer_[idx(j)].size();
    if (now_s - collect_start_s_ >= config_.collect_s || full) {
      for (int j = 0; j < joints_; ++j)
        scale_at_collect_[idx(j)] = applied_[idx(j)];  // both directions
      // Hand the buffers over: the worker reads them only after this.
      phase_.store(static_cast<std::int32_t>(CalibrationState::kIdentifying),
                   std::memory_order_release);
    }
  }
  // Ramp the applied scale towards the target: a bounded rate, so the
  // rendered torque changes smoothly (R F x ramp_per_s per second at most).
  const double step = config_.ramp_per_s * std::max(dt, 0.0);
  for (int j = 0; j < joints_; ++j)
    for (int d = 0; d < 2; ++d) {
      const double target = target_[idx(j)][d].load(std::memory_order_relaxed);
      double& a = applied_[idx(j)][d];
      a = a < target ? std::min(target, a + step) : std::max(target, a - step);
    }
}

CalibrationFigures Recalibration::figures(int joint) const noexcept {
  return figures_[idx(joint)];
}

void Recalibration::identify_joint(int joint, CalibrationReason& why, CalibrationFigures& fig) {
  const std::size_t j = idx(joint);
  const std::size_t n = count_[j];
  fig = CalibrationFigures{};
  fig.samples = n;
  if (n < 100) {
    why = CalibrationReason::kNoData;
    return;
  }
  const auto& b = buffer_[j];
  std::vector<double> t(n), x(n), xd(n), tau(n);
  double x_lo = INFINITY, x_hi = -INFINITY, slide_pos = 0.0, slide_neg = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    t[i] = b[i].t, x[i] = b[i].x, xd[i] = b[i].xd, tau[i] = b[i].tau_in;
    x_lo = std::min(x_lo, x[i]), x_hi = std::max(x_hi, x[i]);
    const double dt = i == 0 ? 0.0 : t[i] - t[i - 1];
    if (xd[i] > kSlidingSpeed) slide_pos += dt;
    if (xd[i] < -kSlidingSpeed) slide_neg += dt;
  }
  fig.span_rad = x_hi - x_lo;
  fig.sliding_s = std::min(slide_pos, slide_neg);
  if (fig.span_rad < config_.min_span_rad || slide_pos < config_.min_sliding_s ||
      slide_neg < config_.min_sliding_s) {
    why = CalibrationReason::kMotionTooSmall;
    return;
  }
  const estimator::ContactCheckConfig free_cfg;
  const auto contact = estimator::check_contact(t, x, xd, tau, free_cfg);
  fig.contact_bins = contact.bins_used;
  if (contact.bins_used < 2) {
    why = CalibrationReason::kMotionTooSmall;
    return;
  }
  if (estimator::shows_contact(contact, free_cfg, nullptr)) {
    why = CalibrationReason::kNotFree;
    return;
  }
  if (level_mode_[j]) {
    fit_level_scale(joint, fig);
  } else {
    // tau_in = k R F over the sliding samples (free motion: the distal torque
    // is the joint's small inertia/damping torque, taken as zero).
    double sff = 0.0, stf = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      if (std::fabs(xd[i]) <= kSlidingSpeed) continue;
      sff += b[i].f_raw * b[i].f_raw;
      stf += b[i].tau_in * b[i].f_raw;
    }
    if (!(sff > 0.0)) {
      why = CalibrationReason::kMotionTooSmall;
      return;
    }
    fig.scale = fig.scale_positive = fig.scale_negative = fig.scale_common = stf / sff;
    double ss_old = 0.0, ss_new = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      const double e_old = b[i].tau_in - scale_at_collect_[j][0] * b[i].f_raw;
      const double e_new = b[i].tau_in - fig.scale * b[i].f_raw;
      ss_old += e_old * e_old, ss_new += e_new * e_new;
    }
    fig.rms_old = std::sqrt(ss_old / static_cast<double>(n));
    fig.rms_new = fig.rms_common = std::sqrt(ss_new / static_cast<double>(n));
  }
  // One verdict for both fits: each direction's scale within the plausible
  // range (the output fit has one scale for both), then a large enough
  // improvement of the residual.
  const auto plausible = [&](double k) { return k >= config_.min_scale && k <= config_.max_scale; };
  if (!plausible(fig.scale_positive) || !plausible(fig.scale_negative)) {
    why = CalibrationReason::kImplausible;
    return;
  }
  if (!(fig.rms_new <= (1.0 - config_.min_improvement) * fig.rms_old)) {
    why = CalibrationReason::kNotBetter;
    return;
  }
  why = CalibrationReason::kNone;
}

double Recalibration::replay_sse(int joint, double k_positive, double k_negative,
                                 std::size_t& scored) {
  const std::size_t j = idx(joint);
  const std::size_t n = count_[j];
  const auto& b = buffer_[j];
  estimator::FrictionModel& model = *replicas_[j];
  const double r = radius_[j];
  // The first samples replay the model's start from the first sample's
  // friction (free motion: tau_in / R), not the routing: left out.
  constexpr double kSettle = 0.3;  // s
  const auto motion = [&](const Sample& s) {
    return estimator::Motion{
        s.t, s.x, s.xd, s.xdd, s.acc_sign, std::fabs(s.tau_in) / r, s.tau_in / r, s.tension};
  };
  model.reset();
  model.set_level_scales(k_positive, k_negative);
  model.preset(b[0].tau_in / r, motion(b[0]));
  double sse = 0.0;
  scored = 0;
  for (std::size_t i = 1; i < n; ++i) {
    const double dt = b[i].t - b[i - 1].t;
    const double f = dt > 0.0 ? model.step(motion(b[i]), dt) : model.friction();
    if (b[i].t - b[0].t < kSettle) continue;
    const double e = b[i].tau_in - r * f;
    sse += e * e;
    ++scored;
  }
  return sse;
}

namespace {

// Golden-section search for the minimum of f over [a, c] (log scale); returns
// the best point and writes its value.
template <class F>
double golden_section(F&& f, double a, double c, int iterations, double& best_value) {
  const double golden = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = c - golden * (c - a), x2 = a + golden * (c - a);
  double f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < iterations; ++i) {
    if (f1 < f2) {
      c = x2, x2 = x1, f2 = f1;
      x1 = c - golden * (c - a);
      f1 = f(x1);
    } else {
      a = x1, x1 = x2, f1 = f2;
      x2 = a + golden * (c - a);
      f2 = f(x2);
    }
  }
  best_value = std::min(f1, f2);
  return f1 < f2 ? x1 : x2;
}

}  // namespace

void Recalibration::fit_level_scale(int joint, CalibrationFigures& fig) {
  const std::size_t j = idx(joint);
  std::size_t scored = 0;
  const auto common = [&](double log_k) {
    const double k = std::exp(log_k);
    return replay_sse(joint, k, k, scored);
  };
  // The replay's error is smooth in k with one valley: a log-spaced scan
  // over the plausible range, then golden-section search around its best.
  constexpr int kScan = 33;
  const double lo = std::log(config_.min_scale), hi = std::log(config_.max_scale);
  const double step = (hi - lo) / (kScan - 1);
  int best = 0;
  double best_sse = INFINITY;
  for (int i = 0; i < kScan; ++i) {
    const double v = common(lo + step * i);
    if (v < best_sse) best_sse = v, best = i;
  }
  double sse = INFINITY;
  double log_k = golden_section(common, lo + step * std::max(best - 1, 0),
                                lo + step * std::min(best + 1, kScan - 1), 30, sse);
  if (best_sse < sse) log_k = lo + step * best, sse = best_sse;
  double log_kp = log_k, log_kn = log_k;
  fig.scale_common = std::exp(log_k);
  const double m_common = static_cast<double>(std::max<std::size_t>(scored, 1));
  fig.rms_common = std::sqrt(sse / m_common);
  if (config_.per_direction) {
    // Each direction's level mostly sets its own direction's samples, so a
    // few rounds of one-dimensional searches from the common scale converge;
    // within +-0.5 in log (x0.6 .. x1.65) of the common scale, and never past
    // the plausible range.
    constexpr double kReach = 0.5;
    for (int round = 0; round < 3; ++round) {
      for (int d = 0; d < 2; ++d) {
        double& target = d == 0 ? log_kp : log_kn;
        const auto along = [&](double v) {
          const double kp = std::exp(d == 0 ? v : log_kp), kn = std::exp(d == 0 ? log_kn : v);
          return replay_sse(joint, kp, kn, scored);
        };
        double v_sse = INFINITY;
        const double v = golden_section(along, std::max(log_k - kReach, lo),
                                        std::min(log_k + kReach, hi), 24, v_sse);
        if (v_sse < sse) target = v, sse = v_sse;
      }
    }
  }
  fig.scale_positive = std::exp(log_kp);
  fig.scale_negative = std::exp(log_kn);
  fig.scale = 0.5 * (fig.scale_positive + fig.scale_negative);
  const double sse_new = replay_sse(joint, fig.scale_positive, fig.scale_negative, scored);
  const double m = static_cast<double>(std::max<std::size_t>(scored, 1));
  const double sse_old =
      replay_sse(joint, scale_at_collect_[j][0], scale_at_collect_[j][1], scored);
  fig.rms_old = std::sqrt(sse_old / m);
  fig.rms_new = std::sqrt(sse_new / m);
}

bool Recalibration::identify_pending() {
  if (phase_.load(std::memory_order_acquire) !=
      static_cast<std::int32_t>(CalibrationState::kIdentifying))
    return false;
  const std::uint32_t mask = mask_.load(std::memory_order_relaxed);
  std::array<CalibrationFigures, kMaxJoints> figs{};
  CalibrationReason first = CalibrationReason::kNone;
  int first_joint = -1;
  for (int j = 0; j < joints_; ++j) {
    if (((mask >> j) & 1U) == 0) continue;
    CalibrationReason why = CalibrationReason::kNone;
    identify_joint(j, why, figs[idx(j)]);
    if (why != CalibrationReason::kNone && first == CalibrationReason::kNone) {
      first = why;
      first_joint = j;
    }
  }
  figures_ = figs;
  // All or nothing: a partly recalibrated instrument would feel inconsistent.
  if (first == CalibrationReason::kNone)
    for (int j = 0; j < joints_; ++j)
      if ((mask >> j) & 1U) {
        target_[idx(j)][0].store(figs[idx(j)].scale_positive, std::memory_order_relaxed);
        target_[idx(j)][1].store(figs[idx(j)].scale_negative, std::memory_order_relaxed);
      }
  reason_.store(static_cast<std::int32_t>(first), std::memory_order_relaxed);
  reason_joint_.store(first_joint, std::memory_order_relaxed);
  phase_.store(
      static_cast<std::int32_t>(first == CalibrationReason::kNone ? CalibrationState::kApplied
                                                                  : CalibrationState::kRefused),
      std::memory_order_release);
  results_.fetch_add(1, std::memory_order_acq_rel);
  return true;
}

}  // namespace tsmh::haptics
