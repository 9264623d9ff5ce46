#include "estimator/fit_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "realtime/quantile.hpp"

namespace tsmh::estimator {
ErrorMetrics error_metrics(std::span<const double> y, std::span<const double> f,
                           const std::function<bool(std::size_t)>& select) {
  ErrorMetrics m;
  double sum_y = 0.0, sum_e = 0.0, sum_e2 = 0.0;
  double e_min = std::numeric_limits<double>::infinity();
  double e_max = -e_min;
  std::size_t n = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    if (!select(i)) continue;
    const double e = y[i] - f[i];
    sum_y += y[i];
    sum_e += e;
    sum_e2 += e * e;
    e_min = std::min(e_min, e);
    e_max = std::max(e_max, e);
    ++n;
  }
  m.samples = n;
  if (n == 0) return m;
  const double mean_y = sum_y / static_cast<double>(n);
  double ss_y = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    if (select(i)) ss_y += (y[i] - mean_y) * (y[i] - mean_y);
  }
  m.rmse = std::sqrt(sum_e2 / static_cast<double>(n));
  m.p2p = e_max - e_min;
  m.bias = sum_e / static_cast<double>(n);
  m.fit_percent = ss_y > 0.0 ? 100.0 * (1.0 - std::sqrt(sum_e2 / ss_y)) : std::nan("");
  return m;
}

ErrorMetrics error_metrics(const FitData& data, std::span<const double> model, SampleRole role) {
  return error_metrics(data.measured, model, [&](std::size_t i) { return data.role[i] == role; });
}

RegimeThresholds regime_thresholds(const FitData& data) {
  RegimeThresholds th;
  std::vector<double> speed, load, pos;
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (data.role[i] == SampleRole::kIgnored) continue;
    speed.push_back(std::fabs(data.motion[i].xd));
    load.push_back(data.motion[i].load);
    pos.push_back(data.motion[i].x);
  }
  // "Near reversal": slower than a tenth of the typical fast speed, and at
  // least 0.05 rad/s so encoder noise at rest does not define the regime.
  th.reversal_speed = std::max(0.05, 0.1 * realtime::quantile(speed, 0.95));
  std::vector<double> moving;
  for (double s : speed)
    if (s > th.reversal_speed) moving.push_back(s);
  th.speed_split = realtime::median(moving);
  th.load_split = realtime::median(load);
  th.position_split = realtime::median(pos);
  th.time_split = data.motion.empty() ? 0.0 : 0.5 * (data.motion.front().t + data.motion.back().t);
  return th;
}

std::vector<RegimeError> regime_errors(const FitData& data, std::span<const double> model,
                                       SampleRole role) {
  const RegimeThresholds th = regime_thresholds(data);
  struct Slice {
    const char* name;
    const char* group;
    std::string where;
    std::function<bool(const Motion&)> in;
  };
  const auto num = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return std::string(buf);
  };
  const double vr = th.reversal_speed;
  const std::vector<Slice> slices = {
      {"accelerating", "acceleration", "|xd| growing (xd and xdd of equal sign)",
       [](const Motion& m) { return m.xd * m.xdd > 0.0; }},
      {"decelerating", "acceleration", "|xd| shrinking (xd and xdd of opposite sign)",
       [](const Motion& m) { return m.xd * m.xdd < 0.0; }},
      {"positive_velocity", "direction", "xd > " + num(vr) + " rad/s",
       [vr](const Motion& m) { return m.xd > vr; }},
      {"negative_velocity", "direction", "xd < -" + num(vr) + " rad/s",
       [vr](const Motion& m) { return m.xd < -vr; }},
      {"near_reversal", "direction", "|xd| <= " + num(vr) + " rad/s",
       [vr](const Motion& m) { return std::fabs(m.xd) <= vr; }},
      {"low_speed", "speed", num(vr) + " < |xd| <= " + num(th.speed_split) + " rad/s",
       [vr, s = th.speed_split](const Motion& m) {
         return std::fabs(m.xd) > vr && std::fabs(m.xd) <= s;
       }},
      {"high_speed", "speed", "|xd| > " + num(th.speed_split) + " rad/s",
       [s = th.speed_split](const Motion& m) { return std::fabs(m.xd) > s; }},
      {"low_load", "load", "load <= " + num(th.load_split) + " N",
       [s = th.load_split](const Motion& m) { return m.load <= s; }},
      {"high_load", "load", "load > " + num(th.load_split) + " N",
       [s = th.load_split](const Motion& m) { return m.load > s; }},
      {"low_position", "position", "x <= " + num(th.position_split) + " rad",
       [s = th.position_split](const Motion& m) { return m.x <= s; }},
      {"high_position", "position", "x > " + num(th.position_split) + " rad",
       [s = th.position_split](const Motion& m) { return m.x > s; }},
      {"early", "time", "t <= " + num(th.time_split) + " s",
       [s = th.time_split](const Motion& m) { return m.t <= s; }},
      {"late", "time", "t > " + num(th.time_split) + " s",
       [s = th.time_split](const Motion& m) { return m.t > s; }},
  };
  const ErrorMetrics all = error_metrics(data, model, role);
  const double total_e2 =
      all.samples > 0 ? all.rmse * all.rmse * static_cast<double>(all.samples) : 0.0;
  std::vector<RegimeError> out;
  for (const auto& s : slices) {
    RegimeError r;
    r.name = s.name;
    r.group = s.group;
    r.where = s.where;
    r.metrics = error_metrics(data.measured, model, [&](std::size_t i) {
      return data.role[i] == role && s.in(data.motion[i]);
    });
    r.mean_error = r.metrics.bias;
    double excess = 0.0;
    std::size_t n = 0;
    for (std::size_t i = 0; i < data.size(); ++i) {
      if (data.role[i] != role || !s.in(data.motion[i])) continue;
      excess += (data.measured[i] - model[i]) * sign_of(model[i]);
      ++n;
    }
    if (n > 0) r.magnitude_excess = excess / static_cast<double>(n);
    if (r.metrics.samples > 0 && total_e2 > 0.0) {
      const double e2 = r.metrics.rmse * r.metrics.rmse * static_cast<double>(r.metrics.samples);
      r.concentration = (e2 / total_e2) /
                        (static_cast<double>(r.metrics.samples) / static_cast<double>(all.samples));
    }
    out.push_back(std::move(r));
  }
  return out;
}

double autocorrelation(std::span<const double> r, std::size_t k) {
  const std::size_t n = r.size();
  if (k >= n) return 0.0;
  double mean = 0.0;
  for (double v : r)
    mean += v;
  mean /= static_cast<double>(n);
  double c0 = 0.0, ck = 0.0;
  for (std::size_t i = 0; i < n; ++i)
    c0 += (r[i] - mean) * (r[i] - mean);
  for (std::size_t i = k; i < n; ++i)
    ck += (r[i] - mean) * (r[i - k] - mean);
  return c0 > 0.0 ? ck / c0 : 0.0;
}

double correlation_time(std::span<const double> r) {
  const std::size_t n = r.size();
  if (n < 10) return 1.0;
  double mean = 0.0;
  for (double v : r)
    mean += v;
  mean /= static_cast<double>(n);
  double c0 = 0.0;
  for (double v : r)
    c0 += (v - mean) * (v - mean);
  if (!(c0 > 0.0)) return 1.0;
  double tau = 1.0;
  const std::size_t max_lag = std::min<std::size_t>(n / 4, 2000);
  for (std::size_t k = 1; k < max_lag; ++k) {
    double ck = 0.0;
    for (std::size_t i = k; i < n; ++i)
      ck += (r[i] - mean) * (r[i - k] - mean);
    const double rho = ck / c0;
    if (rho < 0.05) break;
    tau += 2.0 * rho;
  }
  return tau;
}

double noise_floor(std::span<const double> y) {
  if (y.size() < 3) return std::nan("");
  std::vector<double> d2(y.size() - 2);
  for (std::size_t i = 2; i < y.size(); ++i)
    d2[i - 2] = std::fabs(y[i] - 2.0 * y[i - 1] + y[i - 2]);
  return realtime::median(std::move(d2)) / (0.6745 * std::sqrt(6.0));
}

}  // namespace tsmh::estimator
