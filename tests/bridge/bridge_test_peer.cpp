// A second process for the bridge tests.
//   bridge_test_peer open URL
//       opens LCM at URL; prints "opened" or the BridgeError text; exit 0 / 3.
//   bridge_test_peer publish URL PREFIX COUNT RATE_HZ [truth]
//       publishes COUNT SLAVE_STATE (and SLAVE_TRUTH with the same seq) through
//       a Sender at RATE_HZ with absolute deadlines, then exits after the
//       publish thread has sent everything.
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <string>

#include "bridge/clock.hpp"
#include "bridge/lcm_url.hpp"
#include "bridge/sender.hpp"
#include "test_samples.hpp"

namespace {

int open_mode(const std::string& url) {
  try {
    auto lcm = tsmh::bridge::open_lcm(url);
    std::printf("opened\n");
    return 0;
  } catch (const tsmh::bridge::BridgeError& e) {
    std::printf("%s\n", e.what());
    return 3;
  }
}

int publish_mode(const std::string& url, const std::string& prefix, long count, double rate_hz,
                 bool truth) {
  using namespace tsmh::bridge;
  Sender tx({.url = url, .prefix = prefix});
  auto& states = tx.outbox<SlaveStateSample>();
  auto& truths = tx.outbox<SlaveTruthSample>();
  tx.start();
  const auto period_ns = static_cast<std::int64_t>(1e9 / rate_hz);
  timespec next{};
  clock_gettime(CLOCK_MONOTONIC, &next);
  for (long i = 0; i < count; ++i) {
    const std::int64_t utime = monotonic_utime();
    states.publish(test::make_state(i, utime));
    if (truth) truths.publish(test::make_truth(i, utime));
    next.tv_nsec += period_ns;
    while (next.tv_nsec >= 1'000'000'000) {
      next.tv_nsec -= 1'000'000'000;
      ++next.tv_sec;
    }
    clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
  }
  tx.stop();
  const auto s = states.stats();
  std::printf("published %llu dropped %llu errors %llu\n",
              static_cast<unsigned long long>(s.published),
              static_cast<unsigned long long>(s.dropped_full),
              static_cast<unsigned long long>(s.publish_errors));
  return s.published == static_cast<std::uint64_t>(count) ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "open" && argc == 3) return open_mode(argv[2]);
  if (mode == "publish" && (argc == 6 || argc == 7))
    return publish_mode(argv[2], argv[3], std::atol(argv[4]), std::atof(argv[5]),
                        argc == 7 && std::string(argv[6]) == "truth");
  std::fprintf(stderr, "usage: %s open URL | publish URL PREFIX COUNT RATE_HZ [truth]\n", argv[0]);
  return 2;
}
