// Drift-alarm sweep (a measurement program, not a ctest): runs the
// deployed estimator and the haptic loop's DriftMonitor, sample by sample as
// haptic-server does per SLAVE_STATE, over a virtual-slave CSV.
//   drift_eval PARAMS.yaml DATA.csv [REROUTE_AT_S]
// Prints the alarm's rises (time, scale), the share of samples alarmed and,
// with REROUTE_AT_S, the delay from the re-route to the first alarm after it.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <vector>

#include "estimator/distal_estimator.hpp"
#include "estimator/model_io.hpp"
#include "estimator/recording.hpp"
#include "haptics/drift_monitor.hpp"

int main(int argc, char** argv) try {
  using namespace tsmh;
  if (argc < 3) {
    std::fprintf(stderr, "usage: drift_eval PARAMS.yaml DATA.csv [REROUTE_AT_S]\n");
    return 2;
  }
  const auto rec = estimator::read_recording_csv(argv[2]);
  const double reroute = argc > 3 ? std::atof(argv[3]) : -1.0;
  estimator::DistalTorqueEstimator est(estimator::load_model(argv[1]), rec.radius_m);
  haptics::DriftMonitor drift;
  bool was = false;
  long alarmed = 0, rises = 0;
  double first_after = -1.0, scale_sum = 0.0, scale_max_off = 0.0;
  long judged = 0;
  for (std::size_t i = 0; i < rec.size(); ++i) {
    const auto e = est.update(rec.t[i], rec.x_in[i], rec.tau_in[i]);
    drift.update(rec.t[i], e, rec.radius_m);
    if (drift.judged() && (reroute < 0 || rec.t[i] < reroute)) {
      scale_sum += drift.scale();
      ++judged;
      scale_max_off = std::max(scale_max_off, std::fabs(drift.scale() - 1.0));
    }
    if (drift.alarm()) ++alarmed;
    if (drift.alarm() && !was) {
      ++rises;
      std::printf("alarm at t = %.3f s, scale %.3f\n", rec.t[i], drift.scale());
      if (reroute >= 0 && rec.t[i] >= reroute && first_after < 0) first_after = rec.t[i] - reroute;
    }
    if (!drift.alarm() && was)
      std::printf("cleared at t = %.3f s, scale %.3f\n", rec.t[i], drift.scale());
    was = drift.alarm();
  }
  std::printf(
      "samples %zu (%.1f s), alarmed %.4f %%, rises %ld; before the re-route: mean scale %.3f, "
      "max |scale - 1| %.3f; final scale %.3f",
      rec.size(), rec.t.back() - rec.t.front(), 100.0 * alarmed / rec.size(), rises,
      judged ? scale_sum / judged : 1.0, scale_max_off, drift.scale());
  if (reroute >= 0) std::printf("; detection %.3f s after the re-route", first_after);
  std::printf("\n");
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "drift_eval: %s\n", e.what());
  return 1;
}
