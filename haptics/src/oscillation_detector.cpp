#include "haptics/oscillation_detector.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tsmh::haptics {
namespace {

constexpr double kPi = 3.14159265358979323846;

void require(bool ok, const char* field, const char* what) {
  if (!ok) throw std::invalid_argument(std::string("safety.oscillation.") + field + ": " + what);
}

}  // namespace

void validate(const OscillationConfig& c, double rate_hz) {
  require(c.band_low_hz > 0.0 && std::isfinite(c.band_low_hz), "band_low_hz",
          "must be a number > 0");
  require(c.band_high_hz > c.band_low_hz && c.band_high_hz < 0.45 * rate_hz, "band_high_hz",
          "must lie above band_low_hz and below 0.45 x rate_hz");
  require(c.threshold_nm > 0.0 && std::isfinite(c.threshold_nm), "threshold_nm",
          "must be a number > 0");
  require(c.min_crossings >= 1 && c.min_crossings <= 1000, "min_crossings",
          "must be within 1..1000");
  require(c.window_s > 0.0 && c.window_s <= 10.0, "window_ms", "must be within (0, 10000]");
  require(c.fade_s > 0.0 && c.fade_s <= 10.0, "fade_ms", "must be within (0, 10000]");
  require(c.hold_s >= 0.0 && c.hold_s <= 60.0, "hold_ms", "must be within [0, 60000]");
  require(c.recover_s > 0.0 && c.recover_s <= 60.0, "recover_ms", "must be within (0, 60000]");
}

Biquad Biquad::lowpass(double fc_hz, double fs_hz) noexcept {
  const double k = std::tan(kPi * fc_hz / fs_hz);
  const double q = 1.0 / std::sqrt(2.0);
  const double norm = 1.0 / (1.0 + k / q + k * k);
  Biquad b;
  b.b0 = k * k * norm;
  b.b1 = 2.0 * b.b0;
  b.b2 = b.b0;
  b.a1 = 2.0 * (k * k - 1.0) * norm;
  b.a2 = (1.0 - k / q + k * k) * norm;
  return b;
}

Biquad Biquad::highpass(double fc_hz, double fs_hz) noexcept {
  const double k = std::tan(kPi * fc_hz / fs_hz);
  const double q = 1.0 / std::sqrt(2.0);
  const double norm = 1.0 / (1.0 + k / q + k * k);
  Biquad b;
  b.b0 = norm;
  b.b1 = -2.0 * norm;
  b.b2 = norm;
  b.a1 = 2.0 * (k * k - 1.0) * norm;
  b.a2 = (1.0 - k / q + k * k) * norm;
  return b;
}

OscillationDetector::OscillationDetector(int joints, const OscillationConfig& c, double rate_hz)
    : joints_(joints), c_(c) {
  if (joints < 1 || joints > static_cast<int>(kMaxJoints))
    throw std::invalid_argument("oscillation detector: joint count must be 1.." +
                                std::to_string(kMaxJoints));
  validate(c_, rate_hz);
  for (int j = 0; j < joints_; ++j) {
    hp_[static_cast<std::size_t>(j)] = Biquad::highpass(c_.band_low_hz, rate_hz);
    lp_[static_cast<std::size_t>(j)] = Biquad::lowpass(c_.band_high_hz, rate_hz);
  }
}

double OscillationDetector::band_rms(int joint) const noexcept {
  return std::sqrt(energy_[static_cast<std::size_t>(joint)]);
}

void OscillationDetector::reset_signal() noexcept {
  for (int j = 0; j < joints_; ++j) {
    const auto i = static_cast<std::size_t>(j);
    hp_[i].z1 = hp_[i].z2 = lp_[i].z1 = lp_[i].z2 = 0.0;
    energy_[i] = last_band_[i] = 0.0;
    crossings_[i] = 0;
  }
}

double OscillationDetector::update(const JointArray& rendered, double dt_s) noexcept {
  if (!c_.enabled) return 1.0;
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) dt_s = 0.0;
  const double alpha = std::min(1.0, dt_s / c_.window_s);
  const double trip = c_.threshold_nm * c_.threshold_nm;
  const double quiet = 0.25 * trip;  // (threshold / 2)^2: hysteresis
  bool above = false, all_quiet = true;
  for (int j = 0; j < joints_; ++j) {
    const auto i = static_cast<std::size_t>(j);
    const double x = std::isfinite(rendered[i]) ? rendered[i] : 0.0;
    const double band = lp_[i].step(hp_[i].step(x));
    energy_[i] += alpha * (band * band - energy_[i]);
    if (!std::isfinite(energy_[i])) energy_[i] = 0.0;  // never latch on a bad value
    // Swings are counted with hysteresis (beyond +-threshold/2, which any
    // oscillation at the threshold's RMS exceeds), so noise riding on the
    // decay of a step never adds up to crossings.
    const double h = 0.5 * c_.threshold_nm;
    const double side = band > h ? 1.0 : band < -h ? -1.0 : last_band_[i];
    if (energy_[i] > trip) {
      if (side != last_band_[i] && last_band_[i] != 0.0) ++crossings_[i];
    } else {
      crossings_[i] = 0;
    }
    last_band_[i] = side;
    above = above || crossings_[i] >= c_.min_crossings;
    all_quiet = all_quiet && energy_[i] < quiet;
  }
  if (!tripped_ && above) {
    tripped_ = true;
    tripped_for_s_ = 0.0;
    ++trips_;
  } else if (tripped_) {
    tripped_for_s_ += dt_s;
    if (tripped_for_s_ >= c_.hold_s && all_quiet) tripped_ = false;
  }
  gain_ = tripped_ ? std::max(0.0, gain_ - dt_s / c_.fade_s)
                   : std::min(1.0, gain_ + dt_s / c_.recover_s);
  return gain_;
}

}  // namespace tsmh::haptics
