#pragma once
// A Kalman filter for a sampled signal whose N-th derivative is white noise
// (N = 3: white jerk, the state is value, rate, second rate; N = 4: white
// snap, the third rate joins the state). It is discretised for each actual
// sample interval, so uneven time stamps and dropped samples are handled
// exactly, and its covariance is the estimate's own uncertainty, which the
// differentiator uses to decide when sgn(xdd) is known. Never allocates.

#include <array>
#include <cmath>
#include <cstddef>
#include <utility>

namespace tsmh::estimator {

template <std::size_t N>
class PolyKalman {
 public:
  using Vec = std::array<double, N>;
  using Mat = std::array<Vec, N>;

  /// noise_psd: spectral density of the N-th derivative; r: measurement variance.
  PolyKalman(double noise_psd, double r) noexcept : q_(noise_psd), r_(r) {}

  /// Starts at value x with every rate 0 and the given prior spreads of the rates.
  void start(double x, const Vec& prior_sd) noexcept {
    s_ = {};
    s_[0] = x;
    p_ = {};
    p_[0][0] = r_;
    for (std::size_t i = 1; i < N; ++i)
      p_[i][i] = prior_sd[i] * prior_sd[i];
  }

  /// Predicts over dt > 0 and corrects with the measurement z.
  void update(double dt, double z) noexcept {
    predict_state(dt);
    const auto c = taylor(dt);
    // P <- F P F^T + Q (upper triangle, mirrored).
    Mat fp{};
    for (std::size_t i = 0; i < N; ++i)
      for (std::size_t j = 0; j < N; ++j) {
        double v = 0.0;
        for (std::size_t k = i; k < N; ++k)
          v += c[k - i] * p_[k][j];
        fp[i][j] = v;
      }
    for (std::size_t i = 0; i < N; ++i)
      for (std::size_t j = i; j < N; ++j) {
        double v = 0.0;
        for (std::size_t k = j; k < N; ++k)
          v += fp[i][k] * c[k - j];
        // White N-th derivative: Q[i][j] = q dt^(2N-1-i-j) / ((2N-1-i-j) (N-1-i)! (N-1-j)!),
        // written with the Taylor coefficients.
        const std::size_t a = N - 1 - i, b = N - 1 - j;
        v += q_ * c[a] * c[b] * dt / static_cast<double>(a + b + 1);
        p_[i][j] = v;
        p_[j][i] = v;
      }
    const double inv = 1.0 / (p_[0][0] + r_);
    const double innovation = z - s_[0];
    Vec k{};
    for (std::size_t i = 0; i < N; ++i) {
      k[i] = p_[i][0] * inv;
      s_[i] += k[i] * innovation;
    }
    const Vec row0 = p_[0];
    for (std::size_t i = 0; i < N; ++i)
      for (std::size_t j = i; j < N; ++j) {
        p_[i][j] -= k[i] * row0[j];
        p_[j][i] = p_[i][j];
      }
  }

  /// Predicts over dt > 0 and corrects with z using a given gain, leaving the
  /// covariance alone: the steady-state filter for that interval.
  void update_with_gain(double dt, double z, const Vec& gain) noexcept {
    // On a local copy, written back once: element-wise stores followed by
    // vector loads of the same array stall store forwarding.
    Vec s = predicted(dt);
    const double innovation = z - s[0];
    for (std::size_t i = 0; i < N; ++i)
      s[i] += gain[i] * innovation;
    s_ = s;
  }

  /// The gain and covariance this filter converges to when every interval is
  /// dt (the covariance recursion run to its fixed point; data-independent).
  /// `warm`: a covariance to start the recursion from (e.g. the fixed point
  /// for a nearby interval), or nullptr.
  static std::pair<Vec, Mat> steady_state(double noise_psd, double r, double dt,
                                          const Mat* warm = nullptr) noexcept {
    PolyKalman f(noise_psd, r);
    Vec prior{};
    for (std::size_t i = 1; i < N; ++i)
      prior[i] = 1.0;
    f.start(0.0, prior);
    if (warm) f.p_ = *warm;
    // After a correction P+[i][0] = K[i] r, so the posterior gives the gain.
    double k0 = 0.0;
    for (int i = 0; i < 20000; ++i) {
      f.update(dt, 0.0);
      const double next = f.p_[0][0] / f.r_;
      if (i > 50 && std::fabs(next - k0) <= 1e-12 * next) break;
      k0 = next;
    }
    Vec gain{};
    for (std::size_t i = 0; i < N; ++i)
      gain[i] = f.p_[i][0] / f.r_;
    return {gain, f.p_};
  }

  const Vec& state() const noexcept { return s_; }
  const Mat& covariance() const noexcept { return p_; }
  /// The state predicted dt ahead, F s (F[i][j] = dt^(j-i) / (j-i)!).
  Vec predicted(double dt) const noexcept {
    const auto c = taylor<N>(dt);
    Vec out;
    for (std::size_t i = 0; i < N; ++i) {
      double v = 0.0;
      for (std::size_t j = i; j < N; ++j)
        v += c[j - i] * s_[j];
      out[i] = v;
    }
    return out;
  }

 private:
  // dt^k / k! for k < M, with the divisions done at compile time.
  template <std::size_t M = 2 * N>
  static std::array<double, M> taylor(double dt) noexcept {
    constexpr auto inverse = [] {
      std::array<double, M> v{};
      for (std::size_t k = 1; k < M; ++k)
        v[k] = 1.0 / static_cast<double>(k);
      return v;
    }();
    std::array<double, M> c{};
    c[0] = 1.0;
    for (std::size_t k = 1; k < M; ++k)
      c[k] = c[k - 1] * dt * inverse[k];
    return c;
  }
  void predict_state(double dt) noexcept { s_ = predicted(dt); }

  double q_, r_;
  Vec s_{};
  Mat p_{};
};

}  // namespace tsmh::estimator
