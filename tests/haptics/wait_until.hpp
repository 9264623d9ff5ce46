#pragma once
// Polling for a condition in the end-to-end tests: the other processes run
// on their own, so the test looks every `poll` until `done()` or the timeout.

#include <chrono>
#include <thread>

namespace tsmh::haptics::test {

/// True as soon as done() is; false when `timeout` passed first.
template <class Pred>
bool wait_until(Pred done, std::chrono::milliseconds timeout,
                std::chrono::milliseconds poll = std::chrono::milliseconds(1)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(poll);
  }
  return true;
}

}  // namespace tsmh::haptics::test
