// The differentiator on a quantised (2 pi/40960 rad), noisy, 1 kHz encoder
// signal: velocity error and delay measured and bounded, uneven time stamps,
// and an acceleration sign that does not chatter.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <random>
#include <string>

#include "estimator/corrections.hpp"
#include "estimator/differentiator.hpp"

namespace tsmh::estimator {
namespace {

constexpr double kQuantum = 2.0 * std::numbers::pi / 40960.0;
constexpr double kW = 2.0 * std::numbers::pi * 0.5;

double quantise(double x) {
  return std::round(x / kQuantum) * kQuantum;
}

struct Trace {
  std::vector<double> t, xd_est, xd_true, xdd_true;
  std::vector<double> sign;
};

Trace run(const std::vector<double>& times, double noise_std, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, noise_std > 0 ? noise_std : 1.0);
  Differentiator d(DifferentiatorConfig{.position_noise = noise_std});
  Trace r;
  for (double t : times) {
    const double x = 0.8 * std::sin(kW * t) + (noise_std > 0 ? noise(rng) : 0.0);
    const auto der = d.update(t, quantise(x));
    EXPECT_TRUE(der.valid);
    r.t.push_back(t);
    r.xd_est.push_back(der.xd);
    r.xd_true.push_back(0.8 * kW * std::cos(kW * t));
    r.xdd_true.push_back(-0.8 * kW * kW * std::sin(kW * t));
    r.sign.push_back(der.acc_sign);
  }
  return r;
}

std::vector<double> uniform_times(double duration, double dt) {
  std::vector<double> t;
  for (int i = 0; i * dt <= duration; ++i)
    t.push_back(i * dt);
  return t;
}

double rms_error_after(const Trace& r, double t0, double delay) {
  double sum = 0.0;
  int n = 0;
  for (std::size_t i = 0; i < r.t.size(); ++i) {
    if (r.t[i] < t0) continue;
    const double truth = 0.8 * kW * std::cos(kW * (r.t[i] - delay));
    sum += (r.xd_est[i] - truth) * (r.xd_est[i] - truth);
    ++n;
  }
  return std::sqrt(sum / n);
}

TEST(Differentiator, VelocityErrorOnQuantisedNoisySignalIsSmall) {
  const Trace r = run(uniform_times(10.0, 1e-3), 2e-5, 1);
  const double err = rms_error_after(r, 1.0, 0.0);
  RecordProperty("velocity_rms_error_rad_s", std::to_string(err));
  // Peak velocity 2.5 rad/s; documented noise about 0.01 rad/s RMS.
  EXPECT_LT(err, 0.02);
}

TEST(Differentiator, DelayIsAFewMilliseconds) {
  const Trace r = run(uniform_times(10.0, 1e-3), 0.0, 2);
  double best_delay = 0.0, best = 1e9;
  for (double delay = -0.01; delay <= 0.02; delay += 1e-4) {
    const double e = rms_error_after(r, 1.0, delay);
    if (e < best) best = e, best_delay = delay;
  }
  RecordProperty("velocity_delay_ms", std::to_string(best_delay * 1e3));
  EXPECT_LT(std::fabs(best_delay), 0.003);
}

TEST(Differentiator, AccelerationDelayIsAFewMilliseconds) {
  // The acceleration channel (white snap) follows constant jerk without lag;
  // on a 0.5 Hz sine its best-matching delay is a few ms, and its noise is
  // the acc_sd it reports.
  Differentiator d;
  std::vector<double> t, a;
  for (double ti : uniform_times(10.0, 1e-3)) {
    t.push_back(ti);
    a.push_back(d.update(ti, quantise(0.8 * std::sin(kW * ti))).xdd);
  }
  double best_delay = 0.0, best = 1e9;
  for (double delay = -0.01; delay <= 0.03; delay += 1e-4) {
    double se = 0.0;
    int n = 0;
    for (std::size_t i = 1000; i < t.size(); ++i) {
      const double truth = -0.8 * kW * kW * std::sin(kW * (t[i] - delay));
      se += (a[i] - truth) * (a[i] - truth);
      ++n;
    }
    if (std::sqrt(se / n) < best) best = std::sqrt(se / n), best_delay = delay;
  }
  RecordProperty("acceleration_delay_ms", std::to_string(best_delay * 1e3));
  RecordProperty("acceleration_rms_error_rad_s2", std::to_string(best));
  RecordProperty("acceleration_sd_reported", std::to_string(d.last().acc_sd));
  EXPECT_LT(std::fabs(best_delay), 0.005);
  EXPECT_LT(best, 2.0 * d.last().acc_sd);
}

TEST(Differentiator, UnevenTimeStampsAndDroppedSamples) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(0.6e-3, 1.4e-3);
  std::uniform_int_distribution<int> drop(0, 49);
  std::vector<double> times{0.0};
  while (times.back() < 10.0)
    times.push_back(times.back() + jitter(rng) + (drop(rng) == 0 ? 0.02 : 0.0));
  const Trace r = run(times, 2e-5, 4);
  const double err = rms_error_after(r, 1.0, 0.0);
  RecordProperty("velocity_rms_error_rad_s", std::to_string(err));
  EXPECT_LT(err, 0.03);
}

TEST(Differentiator, HardAccelerationSignFollowsTruthWithoutChatter) {
  // The paper's switch (SignMode::kHard): -1, 0 or +1 with hysteresis.
  Differentiator d(DifferentiatorConfig{.position_noise = 2e-5, .sign_mode = SignMode::kHard});
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 2e-5);
  std::vector<double> sign, xdd_true;
  for (double t : uniform_times(10.0, 1e-3)) {
    sign.push_back(d.update(t, quantise(0.8 * std::sin(kW * t) + noise(rng))).acc_sign);
    xdd_true.push_back(-0.8 * kW * kW * std::sin(kW * t));
  }
  // From t = 1.5 s, mid-way between crossings of xdd (which cross at whole seconds).
  int transitions = 0, reversals = 0, true_flips = 0;
  double last_nonzero = sign[1500], wrong_time = 0.0;
  for (std::size_t i = 1501; i < sign.size(); ++i) {
    transitions += sign[i] != sign[i - 1];
    true_flips += (xdd_true[i] > 0) != (xdd_true[i - 1] > 0);
    if (sign[i] != 0.0) {
      if (last_nonzero != 0.0 && sign[i] != last_nonzero) ++reversals;
      last_nonzero = sign[i];
    }
    if (sign[i] == -(xdd_true[i] > 0 ? 1.0 : -1.0)) wrong_time += 1e-3;
  }
  EXPECT_EQ(reversals, true_flips) << "the sign reverses once per true zero crossing";
  EXPECT_LE(transitions, 3 * true_flips) << "chatter";
  const double mean_wrong = wrong_time / true_flips;
  RecordProperty("acc_sign_wrong_ms_per_crossing", std::to_string(mean_wrong * 1e3));
  EXPECT_LT(mean_wrong, 0.06);
}

TEST(Differentiator, SmoothSignIsCertainAwayFromCrossingsAndQuickAtThem) {
  const Trace r = run(uniform_times(10.0, 1e-3), 2e-5, 5);
  // +-1 with the true sign whenever |xdd| is clearly resolved (> 0.5 rad/s^2,
  // jerk 25 rad/s^3 here: 20 ms from a crossing), and never more than 5 ms
  // on the wrong side of a crossing.
  double wrong_time = 0.0;
  int crossings = 0;
  for (std::size_t i = 1500; i < r.t.size(); ++i) {
    const double truth = r.xdd_true[i] > 0 ? 1.0 : -1.0;
    crossings += (r.xdd_true[i] > 0) != (r.xdd_true[i - 1] > 0);
    if (std::fabs(r.xdd_true[i]) > 0.5) {
      EXPECT_EQ(r.sign[i], truth) << "t = " << r.t[i];
    }
    if (r.sign[i] * truth < -0.5) wrong_time += 1e-3;
  }
  RecordProperty("smooth_sign_wrong_ms_per_crossing", std::to_string(1e3 * wrong_time / crossings));
  EXPECT_LE(wrong_time / crossings, 0.005);
}

TEST(Differentiator, AccelerationSignIsZeroAtRestAndAveragesZeroAtConstantVelocity) {
  for (SignMode mode : {SignMode::kSmooth, SignMode::kHard}) {
    CorrectedDifferentiator d(DifferentiatorConfig{.sign_mode = mode});
    double sum = 0.0;
    int moving = 0, nonzero_at_rest = 0, transitions = 0;
    double last = 0.0;
    for (int i = 0; i < 20000; ++i) {
      const double t = i * 1e-3;
      const double x = i < 10000 ? 0.3 * t : 3.0;  // constant velocity, then rest
      const auto der = d.update(t, quantise(x));
      if (i > 500 && i < 9700) {
        sum += der.acc_sign;
        ++moving;
        transitions += der.acc_sign != last;
      }
      // At rest the encoder stops changing; after still_time the sign is
      // exactly 0, so lambda sgn(xdd) cannot drive eq. (4).
      if (t > 10.0 + d.rest().still_time() && der.acc_sign != 0.0) {
        ++nonzero_at_rest;
      }
      last = der.acc_sign;
    }
    EXPECT_EQ(nonzero_at_rest, 0);
    // Quantisation makes the estimate jitter around zero at constant speed:
    // the smooth sign averages to about zero (the model is linear in it), the
    // hard one stays at 0.
    RecordProperty(mode == SignMode::kHard ? "hard_mean_sign" : "smooth_mean_sign",
                   std::to_string(sum / moving));
    EXPECT_LT(std::fabs(sum / moving), 0.15) << "mode " << static_cast<int>(mode);
    if (mode == SignMode::kHard) {
      EXPECT_LE(transitions, 2);
    }
  }
}

// The corrections act in CorrectedDifferentiator alone: after a stop the
// plain filter's sign still follows its ringing acceleration estimate, and
// the corrected one is exactly 0 once the encoder has been still for the
// rest time; while moving the two are the same sign.
TEST(Differentiator, ThePlainFilterAppliesNoCorrection) {
  Differentiator plain;
  CorrectedDifferentiator corrected;
  int plain_nonzero_at_rest = 0, corrected_nonzero_at_rest = 0, differ_moving = 0;
  for (int i = 0; i < 12000; ++i) {
    const double t = i * 1e-3;
    const double x = quantise(i < 10000 ? 0.3 * t : 3.0);
    const Derivatives p = plain.update(t, x);
    const Derivatives c = corrected.update(t, x);
    if (t > 10.0 + corrected.rest().still_time() + 0.01 && t < 10.3) {
      plain_nonzero_at_rest += p.acc_sign != 0.0;
      corrected_nonzero_at_rest += c.acc_sign != 0.0;
    }
    if (t > 1.0 && t < 9.0) differ_moving += p.acc_sign != c.acc_sign || p.xdd != c.xdd;
  }
  EXPECT_GT(plain_nonzero_at_rest, 100);
  EXPECT_EQ(corrected_nonzero_at_rest, 0);
  EXPECT_EQ(differ_moving, 0);
}

// The rest time: automatic by default, kRestTime at kReferenceQuantum and
// with the cube root of the quantum elsewhere; a value given is used as is,
// 0 turns it off.
TEST(Differentiator, RestTimeIsAutomaticUnlessGiven) {
  const auto rest_time = [](double quantum, double still_time) {
    CorrectionsConfig corrections;
    corrections.still_time = still_time;
    return CorrectedDifferentiator(DifferentiatorConfig{.quantum = quantum}, corrections)
        .rest()
        .still_time();
  };
  EXPECT_EQ(CorrectedDifferentiator{}.rest().still_time(), kRestTime);
  EXPECT_DOUBLE_EQ(rest_time(8.0 * kReferenceQuantum, -1.0), 2.0 * kRestTime);
  EXPECT_DOUBLE_EQ(rest_time(kReferenceQuantum / 27.0, -1.0), kRestTime / 3.0);
  EXPECT_EQ(rest_time(kReferenceQuantum, 0.02), 0.02);
  EXPECT_EQ(rest_time(kReferenceQuantum, 0.0), 0.0);
}

TEST(Differentiator, ScheduledGainsMatchTheFullRecursionOnceSettled) {
  // exact_covariance false uses the steady-state gain for each interval; on
  // jittered intervals with drops it must agree with the full recursion.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(0.6e-3, 1.4e-3);
  std::uniform_int_distribution<int> drop(0, 49);
  Differentiator fast, full(DifferentiatorConfig{.exact_covariance = true});
  double t = 0.0, worst_v = 0.0, worst_a = 0.0, se_a = 0.0;
  int n = 0;
  for (int i = 0; i < 10000; ++i) {
    t += jitter(rng) + (drop(rng) == 0 ? 0.02 : 0.0);
    const double x = quantise(0.8 * std::sin(kW * t));
    const auto a = fast.update(t, x), b = full.update(t, x);
    if (t > 1.0) {
      worst_v = std::max(worst_v, std::fabs(a.xd - b.xd));
      worst_a = std::max(worst_a, std::fabs(a.xdd - b.xdd));
      se_a += (a.xdd - b.xdd) * (a.xdd - b.xdd);
      ++n;
    }
  }
  RecordProperty("max_velocity_difference", std::to_string(worst_v));
  RecordProperty("max_acceleration_difference", std::to_string(worst_a));
  EXPECT_LT(worst_v, 0.02);  // rad/s, of 2.5 peak
  // Right after a 20 ms drop the full recursion trusts the new sample more
  // than a filter settled at 20 ms intervals: the largest gap is there.
  EXPECT_LT(worst_a, 0.5);  // rad/s^2, of 7.9 peak
  RecordProperty("rms_acceleration_difference", std::to_string(std::sqrt(se_a / n)));
  EXPECT_LT(std::sqrt(se_a / n), 0.1);  // below the estimate's own sd (0.16)
}

// The steady-state step runs the four channels fused, in vector pairs (the
// 1 kHz loop's hot path); it must compute exactly what each channel's
// PolyKalman::update_with_gain computes with the gains steady_gains() reports,
// bit for bit, on uneven intervals across the table (fine and coarse part),
// in all three sign modes and without the slow or the fine channel.
TEST(Differentiator, SteadyStateStepIsPolyKalmanWithTheTableGainsBitForBit) {
  const auto same = [](double a, double b) {
    std::uint64_t x, y;
    std::memcpy(&x, &a, sizeof x);
    std::memcpy(&y, &b, sizeof y);
    return x == y;
  };
  for (const SignMode mode : {SignMode::kSmooth, SignMode::kSmoothFast, SignMode::kHard}) {
    for (const auto& [slow_psd, fine_psd] : {std::pair{1e-3, 1e5}, {0.0, 1e5}, {1e-3, 0.0}}) {
      DifferentiatorConfig cfg{.fine_psd = fine_psd, .slow_jerk_psd = slow_psd, .sign_mode = mode};
      Differentiator d(cfg);
      const double r = cfg.quantum * cfg.quantum / 12.0;
      PolyKalman<3> velocity(cfg.jerk_psd, r), slow(slow_psd > 0.0 ? slow_psd : 1.0, r);
      PolyKalman<4> acceleration(cfg.snap_psd, r);
      PolyKalman<5> fine(fine_psd > 0.0 ? fine_psd : 1.0, r);
      const bool use_fine = mode == SignMode::kSmooth && fine_psd > 0.0;
      // A reproducible sequence of intervals (not std::uniform_*, whose
      // output is the library's own): 0.3-1.7 ms, now and then 2-20 ms.
      std::uint64_t lcg = 12345;
      const auto uniform = [&lcg] {
        lcg = lcg * 6364136223846793005ull + 1442695040888963407ull;
        return static_cast<double>(lcg >> 11) * 0x1.0p-53;
      };
      double t = 100.0;
      int mismatches = 0, steady = 0;
      for (int i = 0; i < 20000; ++i) {
        const double x = quantise(0.6 * std::sin(2.5 * t) + 0.2 * std::sin(8.2 * t));
        const double dt =
            uniform() < 0.02 ? 0.002 + 0.018 * uniform() : 0.3e-3 + 1.4e-3 * uniform();
        const double t_prev = t;
        if (i > 0) t += dt;
        const Derivatives out = d.update(t, x);
        if (i == 0) {
          velocity.start(x, {0.0, 10.0, 100.0});
          acceleration.start(x, {0.0, 10.0, 100.0, 1000.0});
          slow.start(x, {0.0, 10.0, 100.0});
          fine.start(x, {0.0, 10.0, 100.0, 1000.0, 10000.0});
          continue;
        }
        // The first 100 intervals run the full recursion (the settling).
        if (i <= 100) {
          velocity.update(t - t_prev, x);
          acceleration.update(t - t_prev, x);
          if (mode == SignMode::kSmooth && slow_psd > 0.0) slow.update(t - t_prev, x);
          if (use_fine) fine.update(t - t_prev, x);
          continue;
        }
        const auto g = d.steady_gains(t - t_prev);
        velocity.update_with_gain(t - t_prev, x, g.velocity);
        acceleration.update_with_gain(t - t_prev, x, g.acceleration);
        slow.update_with_gain(t - t_prev, x, g.slow);
        fine.update_with_gain(t - t_prev, x, g.fine);
        ++steady;
        if (!same(out.x, velocity.state()[0]) || !same(out.xd, velocity.state()[1]) ||
            !same(out.xdd, acceleration.state()[2]) || !same(out.acc_sd, g.acc_sd))
          ++mismatches;
        if (mode != SignMode::kHard) {
          // The plain differentiator's sign: the ramp.
          double xdd = acceleration.state()[2];
          double sign = std::clamp(xdd * g.inv_width, -1.0, 1.0);
          if (use_fine) {
            const double f_xdd = fine.state()[2];
            const double k = std::min(1.0, std::fabs(xdd - f_xdd) * g.inv_fine_consistency);
            sign = k * k * sign + (1.0 - k * k) * std::clamp(f_xdd * g.fine_inv_width, -1.0, 1.0);
            xdd = k * k * xdd + (1.0 - k * k) * f_xdd;
          }
          if (mode == SignMode::kSmooth && slow_psd > 0.0) {
            const double s_xdd = slow.state()[2];
            const double k = std::min(1.0, std::fabs(xdd - s_xdd) * g.inv_consistency);
            sign = k * k * sign + (1.0 - k * k) * std::clamp(s_xdd * g.slow_inv_width, -1.0, 1.0);
          }
          if (out.acc_sign != 0.0 && !same(out.acc_sign, sign)) ++mismatches;
        }
      }
      EXPECT_EQ(steady, 19899);
      EXPECT_EQ(mismatches, 0) << "mode " << static_cast<int>(mode) << " slow " << slow_psd
                               << " fine " << fine_psd;
    }
  }
}

TEST(Differentiator, SteadyGainsAreZeroWithExactCovariance) {
  const auto g = Differentiator(DifferentiatorConfig{.exact_covariance = true}).steady_gains(1e-3);
  EXPECT_EQ(g.velocity[0], 0.0);
  EXPECT_EQ(g.acc_sd, 0.0);
}

TEST(Differentiator, RejectsNonFiniteAndNonIncreasingTime) {
  Differentiator d;
  EXPECT_TRUE(d.update(0.0, 0.0).valid);
  EXPECT_TRUE(d.update(0.001, 0.001).valid);
  EXPECT_FALSE(d.update(0.001, 0.002).valid);
  EXPECT_FALSE(d.update(0.0005, 0.002).valid);
  EXPECT_FALSE(d.update(0.002, std::nan("")).valid);
  EXPECT_FALSE(d.update(std::numeric_limits<double>::infinity(), 0.0).valid);
  const auto ok = d.update(0.002, 0.002);
  EXPECT_TRUE(ok.valid);
  EXPECT_NEAR(ok.xd, 1.0, 0.5);  // state survived the bad samples
}

// Creeping motion: 20 mrad/s, then +0.03 rad/s^2 for 2 s, then 80 mrad/s.
// Below |xd| = lambda the sign of such accelerations decides which way eq. (4)
// drives the friction state, and the fast channel's noise (sd about 0.2
// rad/s^2) buries them; the slow channel resolves them within a few tenths of
// a second and reads 0 at constant speed.
TEST(Differentiator, SlowChannelResolvesTheSignOfCreepingAccelerations) {
  struct Means {
    double accelerating, cruising_abs;
  };
  const auto run_creep = [](double slow_jerk_psd) {
    Differentiator d(DifferentiatorConfig{.slow_jerk_psd = slow_jerk_psd});
    double acc = 0.0, cruise = 0.0;
    int n_acc = 0, n_cruise = 0;
    for (int i = 0; i < 8000; ++i) {
      const double t = i * 1e-3;
      const double ta = std::clamp(t - 3.0, 0.0, 2.0);
      const double x = 0.02 * t + 0.5 * 0.03 * ta * ta + 0.06 * std::max(0.0, t - 5.0);
      const auto der = d.update(t, quantise(x));
      if (t > 3.5 && t < 5.0) acc += der.acc_sign, ++n_acc;
      if ((t > 1.0 && t < 3.0) || t > 6.0) cruise += std::fabs(der.acc_sign), ++n_cruise;
    }
    return Means{acc / n_acc, cruise / n_cruise};
  };
  const Means with = run_creep(DifferentiatorConfig{}.slow_jerk_psd);
  const Means without = run_creep(0.0);
  RecordProperty("creep_mean_sign_accelerating", std::to_string(with.accelerating));
  RecordProperty("creep_mean_abs_sign_cruising", std::to_string(with.cruising_abs));
  RecordProperty("creep_fast_only_mean_sign_accelerating", std::to_string(without.accelerating));
  RecordProperty("creep_fast_only_mean_abs_sign_cruising", std::to_string(without.cruising_abs));
  EXPECT_GT(with.accelerating, 0.6);
  EXPECT_LT(with.cruising_abs, 0.5);
  EXPECT_GT(with.accelerating - with.cruising_abs, without.accelerating - without.cruising_abs);
}

// A stroke at +1 rad/s, a 60 ms raised-cosine reversal to -1 rad/s starting
// at t = 1 s (peak |xdd| 52 rad/s^2, its jerk jumping at both ends), then a
// stroke at -1 rad/s: the reversals kind of the accuracy suite in small.
struct ReversalTrace {
  double mean_abs_sign_cruising = 0.0;  // 30-300 ms after the reversal's end
  double settled_ms = 0.0;              // last time |sign| > 0.5, up to 300 ms after the end
  double min_sign_mid_reversal = 0.0;   // -sign in the reversal's middle 30 ms
};

ReversalTrace run_reversal(double cruise_window, bool jitter, double dt = 1e-3, double kV = 1.0,
                           double cruise_noise = CorrectionsConfig{}.cruise_noise) {
  constexpr double kStart = 1.0, kDuration = 0.06;
  constexpr double kOmega = std::numbers::pi / kDuration;
  const auto position = [&](double t) {
    if (t < kStart) return kV * t;
    const double tau = std::min(t - kStart, kDuration);
    // v(tau) = kV - kV (1 - cos(omega tau)): from +kV to -kV.
    double x = kV * kStart + kV * tau - kV * (tau - std::sin(kOmega * tau) / kOmega);
    if (t > kStart + kDuration) x -= kV * (t - kStart - kDuration);
    return x;
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> wobble(-2e-4, 2e-4);
  CorrectionsConfig config;
  config.cruise_window = cruise_window;
  config.cruise_noise = cruise_noise;
  CorrectedDifferentiator d({}, config);
  ReversalTrace r;
  const double end = kStart + kDuration;
  double sum = 0.0;
  int n = 0;
  r.min_sign_mid_reversal = 1.0;
  const int samples = static_cast<int>(std::lround(2.0 / dt));
  for (int i = 0; i < samples; ++i) {
    const double t = i * dt + (jitter ? wobble(rng) * dt / 1e-3 : 0.0);
    const auto der = d.update(t, quantise(position(t)));
    if (t > end && t < end + 0.3 && std::fabs(der.acc_sign) > 0.5) r.settled_ms = 1e3 * (t - end);
    if (t > end + 0.03 && t < end + 0.3) sum += std::fabs(der.acc_sign), ++n;
    if (t > kStart + 0.015 && t < kStart + 0.045)
      r.min_sign_mid_reversal = std::min(r.min_sign_mid_reversal, -der.acc_sign);
  }
  r.mean_abs_sign_cruising = sum / n;
  return r;
}

TEST(Differentiator, CruiseHypothesisSettlesTheSignAfterAReversal) {
  // On the stroke after a reversal the true xdd is exactly 0 (the paper's
  // model: no lambda in g, branch (11)), but the acceleration channel rings
  // for 0.1-0.2 s after the reversal's jerk ends. The cruise hypothesis,
  // armed by the channel's inconsistency during the reversal, takes the sign
  // to about 0 once the last cruise_window of samples is a straight line.
  for (bool jitter : {false, true}) {
    const ReversalTrace with = run_reversal(CorrectionsConfig{}.cruise_window, jitter);
    const ReversalTrace without = run_reversal(0.0, jitter);
    const std::string tag = jitter ? "_jittered" : "";
    RecordProperty("reversal_mean_abs_sign_cruising" + tag,
                   std::to_string(with.mean_abs_sign_cruising));
    RecordProperty("reversal_mean_abs_sign_cruising_without" + tag,
                   std::to_string(without.mean_abs_sign_cruising));
    RecordProperty("reversal_sign_settled_ms" + tag, std::to_string(with.settled_ms));
    EXPECT_LT(with.mean_abs_sign_cruising, 0.15) << tag;
    EXPECT_GT(without.mean_abs_sign_cruising, 0.3) << tag;
    EXPECT_LT(with.settled_ms, 50.0) << tag;
    // Inside the reversal (|xdd| 35-52 rad/s^2) the sign stays certain.
    EXPECT_EQ(with.min_sign_mid_reversal, 1.0) << tag;
  }
}

TEST(Differentiator, CruiseHypothesisAtAHighSampleRate) {
  // At 5 kHz the 40 ms window would hold 200 samples; the ring keeps the
  // newest 127 (25 ms) and the sums must stay those of the samples in it.
  const ReversalTrace with = run_reversal(CorrectionsConfig{}.cruise_window, true, 2e-4);
  RecordProperty("reversal_mean_abs_sign_cruising_5khz",
                 std::to_string(with.mean_abs_sign_cruising));
  EXPECT_LT(with.mean_abs_sign_cruising, 0.15);
  EXPECT_EQ(with.min_sign_mid_reversal, 1.0);
}

TEST(Differentiator, CruiseTestToleratesTheEncodersSawtooth) {
  // At 0.4584 rad/s the encoder advances 2.988 counts per sample: its error
  // is a sawtooth slipping by a count every 80 ms, not white noise. Taken as
  // white (cruise_noise 1) each slip made the test reject the cruise and the
  // ringing sign came back; the deployed cruise_noise takes the slips
  // (mean |sign| on the stroke 0.14 against 0.42).
  const double window = CorrectionsConfig{}.cruise_window;
  for (bool jitter : {false, true}) {
    const ReversalTrace tolerant = run_reversal(window, jitter, 1e-3, 0.4584);
    const ReversalTrace white = run_reversal(window, jitter, 1e-3, 0.4584, 1.0);
    const std::string tag = jitter ? "_jittered" : "";
    RecordProperty("sawtooth_mean_abs_sign_cruising" + tag,
                   std::to_string(tolerant.mean_abs_sign_cruising));
    RecordProperty("sawtooth_mean_abs_sign_cruising_white" + tag,
                   std::to_string(white.mean_abs_sign_cruising));
    // Sampling jitter makes the error whiter: both settle there, and the
    // tolerant test no worse than within 0.1 of sign.
    EXPECT_LT(tolerant.mean_abs_sign_cruising, jitter ? 0.1 : 0.5 * white.mean_abs_sign_cruising)
        << tag;
    EXPECT_GT(tolerant.min_sign_mid_reversal, 0.9) << tag;
  }
}

TEST(Differentiator, CruiseHypothesisLeavesSmoothMotionAlone) {
  // On smooth motion the acceleration channel's model holds (its innovations
  // keep their predicted size), the hypothesis is never armed, and the sign
  // is the same bit for bit as without it: the small accelerations of smooth
  // motion keep their sign where it decides eq. (4)'s drive.
  CorrectionsConfig off;
  off.cruise_window = 0.0;
  CorrectedDifferentiator with{{}, CorrectionsConfig{}}, without{{}, off};
  int differ = 0;
  for (int i = 0; i < 20000; ++i) {
    const double t = i * 1e-3;
    const double x = 0.8 * std::sin(kW * t) + 0.3 * std::sin(3.1 * kW * t + 1.0);
    const auto a = with.update(t, quantise(x));
    const auto b = without.update(t, quantise(x));
    differ += a.acc_sign != b.acc_sign || a.xdd != b.xdd;
  }
  EXPECT_EQ(differ, 0);
}

}  // namespace
}  // namespace tsmh::estimator
