// Builds against the installed tsmh package: the paper's friction model over
// one period of a sine, and the installed device profiles.
#include <cmath>
#include <cstdio>
#include <numbers>

#include "estimator/motion.hpp"
#include "estimator/tsm_model.hpp"
#include "master_devices/profile.hpp"
#include "tsmh/version.hpp"

int main() {
  namespace est = tsmh::estimator;
  est::TsmFrictionModel model(est::paper_spec());
  const double dt = 1e-3;
  double peak = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const double t = i * dt;
    const double w = 2.0 * std::numbers::pi;
    est::Motion m;
    m.t = t;
    m.x = std::sin(w * t);
    m.xd = w * std::cos(w * t);
    m.xdd = -w * w * std::sin(w * t);
    m.acc_sign = est::sign_of(m.xdd);
    peak = std::fmax(peak, std::fabs(model.step(m, dt)));
  }
  const auto profiles = tsmh::master_devices::load_profiles(TSMH_DOWNSTREAM_PROFILES);
  std::printf("tsmh %s: paper model peak friction %.3f N, %zu profile(s)\n", TSMH_VERSION, peak,
              profiles.size());
  return std::isfinite(peak) && peak > 0.0 && !profiles.empty() ? 0 : 1;
}
