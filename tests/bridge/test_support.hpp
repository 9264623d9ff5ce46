#pragma once
// Helpers shared by the bridge tests: unique channel prefixes (parallel ctest
// runs must not hear each other), waiting with a deadline.

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <string>
#include <thread>

#include "bridge/lcm_url.hpp"
#include "test_samples.hpp"

namespace tsmh::bridge::test {

/// Concatenates with += only: GCC 12's -Wrestrict misfires on "literal" + std::string.
template <class... Parts>
std::string cat(const Parts&... parts) {
  std::string out;
  (out += ... += parts);
  return out;
}

/// Tests always use the host-local default group with ttl=0, never
/// LCM_DEFAULT_URL: test traffic must not leave this machine. The larger
/// kernel receive buffer (2 MiB, ~1600 small datagrams) keeps exact-count
/// assertions from depending on how long a busy 2-core machine stalls LCM's
/// receive thread.
inline std::string test_url() {
  return cat(kDefaultLcmUrl, "&recv_buf_size=2097152");
}

/// "T<pid>_<n>_<start of the test name>_": unique per process and call, and
/// short: LCM refuses channel names longer than 63 characters.
inline std::string unique_prefix() {
  static int counter = 0;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  return cat("T", std::to_string(getpid()), "_", std::to_string(++counter), "_",
             std::string(info->name()).substr(0, 12), "_");
}

/// Polls `done` every millisecond until it holds or `timeout` passes.
template <class Pred>
bool wait_until(Pred done, std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

}  // namespace tsmh::bridge::test
