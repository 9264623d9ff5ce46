#include "estimator/fit_data.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "estimator/simulate.hpp"
#include "realtime/enum_names.hpp"

namespace tsmh::estimator {
namespace {

void require_finite(const Recording& rec, const std::vector<double>& v, const char* column) {
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) {
      throw DataError(rec.source, 0, column,
                      "sample " + std::to_string(i + 1) + " (t = " +
                          (i < rec.t.size() ? std::to_string(rec.t[i]) : std::string("?")) +
                          " s) is not a finite number");
    }
  }
}

std::string fixed(double v, int digits) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}

}  // namespace

const char* derivatives_name(FitDerivatives d) {
  return realtime::enum_name<FitDerivatives::kDeployed>(d, {"automatic", "offline", "deployed"})
      .data();
}

FitDerivatives derivatives_from_name(const std::string& name) {
  if (name == "auto" || name == "automatic") return FitDerivatives::kAutomatic;
  if (name == "offline") return FitDerivatives::kOffline;
  if (name == "deployed") return FitDerivatives::kDeployed;
  throw std::invalid_argument("derivatives must be auto, offline or deployed, not '" + name + "'");
}

std::size_t FitData::count(SampleRole r) const {
  return static_cast<std::size_t>(std::count(role.begin(), role.end(), r));
}

std::vector<double> FitData::weights(SampleRole r) const {
  std::vector<double> w(role.size());
  for (std::size_t i = 0; i < role.size(); ++i)
    w[i] = role[i] == r ? 1.0 : 0.0;
  return w;
}

int count_reversals(std::span<const Motion> motion, double speed) {
  int reversals = 0;
  int state = 0;  // last excursion: +1 above +speed, -1 below -speed
  for (const auto& m : motion) {
    const int now = m.xd > speed ? 1 : (m.xd < -speed ? -1 : 0);
    if (now != 0 && state != 0 && now != state) ++reversals;
    if (now != 0) state = now;
  }
  return reversals;
}

FitData prepare_fit_data(const Recording& rec, const SplitConfig& split,
                         const DataRequirements& need, const DifferentiatorConfig& diff,
                         FitDerivatives derivatives, const OfflineDerivativeConfig& offline) {
  check_requirements(rec, {.tau_in = true, .tau_out = true, .radius = true});
  if (rec.x_in.size() != rec.size() || rec.tau_in.size() != rec.size() ||
      rec.tau_out.size() != rec.size())
    throw DataError(rec.source, 0, "", "columns t, x_in, tau_in, tau_out differ in length");
  require_finite(rec, rec.t, "t");
  require_finite(rec, rec.x_in, "x_in");
  require_finite(rec, rec.tau_in, "tau_in");
  require_finite(rec, rec.tau_out, "tau_out");
  for (std::size_t i = 1; i < rec.size(); ++i) {
    if (!(rec.t[i] > rec.t[i - 1]))
      throw DataError(rec.source, 0, "t",
                      "time is not strictly increasing at sample " + std::to_string(i + 1));
  }

  const double duration = rec.size() > 1 ? rec.t.back() - rec.t.front() : 0.0;
  if (rec.size() < need.min_samples || duration < need.min_duration_s) {
    throw DataError(rec.source, 0, "t",
                    "recording too short for identification: " + fixed(duration, 2) + " s, " +
                        std::to_string(rec.size()) + " samples (needs at least " +
                        fixed(need.min_duration_s, 1) + " s and " +
                        std::to_string(need.min_samples) + " samples)");
  }
  const auto [lo, hi] = std::minmax_element(rec.x_in.begin(), rec.x_in.end());
  if (*hi - *lo < need.min_span_rad) {
    throw DataError(rec.source, 0, "x_in",
                    "no motion: the angle spans only " + fixed(*hi - *lo, 5) +
                        " rad (needs at least " + fixed(need.min_span_rad, 3) +
                        " rad, moved back and forth); friction cannot be identified at rest");
  }

  FitData d;
  d.source = rec.source;
  d.radius_m = rec.radius_m;
  // By default exact derivatives when the file has them, else the zero-phase
  // smoother: the fit then finds the physical parameters, not ones bent to
  // imitate the online differentiator's lag.
  if (derivatives == FitDerivatives::kAutomatic)
    derivatives = rec.has_derivatives() ? FitDerivatives::kAutomatic : FitDerivatives::kOffline;
  if (derivatives == FitDerivatives::kAutomatic) {
    d.motion = motion_from_recording(rec, DerivativeSource::kExact, diff);
    d.derivatives = "exact";
  } else if (derivatives == FitDerivatives::kOffline) {
    d.motion = offline_motion(rec, offline);
    d.derivatives = "offline";
  } else {
    d.motion = motion_from_recording(rec, DerivativeSource::kDifferentiator, diff);
    d.derivatives = "deployed";
  }
  d.reversals = count_reversals(d.motion, need.reversal_speed);
  if (d.reversals < need.min_reversals) {
    throw DataError(rec.source, 0, "x_in",
                    "no motion: " + std::to_string(d.reversals) +
                        " velocity reversals faster than " + fixed(need.reversal_speed, 2) +
                        " rad/s (needs at least " + std::to_string(need.min_reversals) +
                        "); identification needs the joint moved back and forth");
  }
  d.measured = rec.measured_friction();
  // The distal load as measured (tau_in / R - F = tau_out / R): models that
  // read it are fitted on it, not on drive less their own friction.
  for (std::size_t i = 0; i < d.size(); ++i) {
    Motion& m = d.motion[i];
    if (std::isfinite(m.drive) && std::isfinite(d.measured[i])) m.distal = m.drive - d.measured[i];
  }

  // Blocks: at least 3 per set after the warm-up.
  const double t0 = rec.t.front() + split.warmup_s;
  const double usable = rec.t.back() - t0;
  d.block_s = std::min(split.block_s, usable / 6.0);
  d.role.resize(rec.size());
  for (std::size_t i = 0; i < rec.size(); ++i) {
    if (rec.t[i] < t0) {
      d.role[i] = SampleRole::kIgnored;
      continue;
    }
    const auto block = static_cast<long>(std::floor((rec.t[i] - t0) / d.block_s));
    d.role[i] = block % 2 == 0 ? SampleRole::kTrain : SampleRole::kValidation;
  }
  return d;
}

}  // namespace tsmh::estimator
