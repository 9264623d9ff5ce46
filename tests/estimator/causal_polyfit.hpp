#pragma once
// online_accuracy's baseline differentiator (a plain reference): never
// deployed, only compared with.

#include <array>
#include <deque>
#include <utility>

namespace tsmh::estimator::accuracy {

// The baseline: causal least-squares quadratics through the samples of the
// last 20 ms (velocity) and the last 100 ms (acceleration), on their actual
// time stamps, and sgn of that acceleration: a Savitzky-Golay differentiator
// evaluated at the newest sample. Only here, for comparison; never deployed.
class CausalPolyFit {
 public:
  // (xd, xdd) at the newest sample t.
  std::pair<double, double> update(double t, double x) {
    window_.push_back({t, x});
    while (t - window_.front().first > kAccelerationSpan)
      window_.pop_front();
    return {fit(t, x, kVelocitySpan)[1], 2.0 * fit(t, x, kAccelerationSpan)[2]};
  }

 private:
  static constexpr double kVelocitySpan = 0.020, kAccelerationSpan = 0.100;
  // a0 + a1 tau + a2 tau^2 through the samples with tau = t_i - t >= -span.
  std::array<double, 3> fit(double t, double x, double span) const {
    double s[5] = {}, r[3] = {};
    for (const auto& [ti, xi] : window_) {
      const double tau = ti - t;
      if (tau < -span) continue;
      const double p[5] = {1.0, tau, tau * tau, tau * tau * tau, tau * tau * tau * tau};
      for (int k = 0; k < 5; ++k)
        s[k] += p[k];
      for (int k = 0; k < 3; ++k)
        r[k] += (xi - x) * p[k];
    }
    if (s[0] < 3.0) return {0.0, 0.0, 0.0};
    // Normal equations [s0 s1 s2; s1 s2 s3; s2 s3 s4] a = r, by Cramer's rule.
    const auto det3 = [](double a, double b, double c, double d, double e, double f, double g,
                         double h, double i) {
      return a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g);
    };
    const double d = det3(s[0], s[1], s[2], s[1], s[2], s[3], s[2], s[3], s[4]);
    if (d == 0.0) return {0.0, 0.0, 0.0};
    const double a1 = det3(s[0], r[0], s[2], s[1], r[1], s[3], s[2], r[2], s[4]) / d;
    const double a2 = det3(s[0], s[1], r[0], s[1], s[2], r[1], s[2], s[3], r[2]) / d;
    return {0.0, a1, a2};
  }
  std::deque<std::pair<double, double>> window_;
};

}  // namespace tsmh::estimator::accuracy
