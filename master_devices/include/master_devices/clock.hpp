#pragma once
// CLOCK_MONOTONIC in nanoseconds: the time base of every DeviceReading.
// clock_gettime() on it is a vDSO call: no syscall, no lock, safe in the loop.

#include <time.h>

#include <cstdint>

namespace tsmh::master_devices {

inline std::int64_t monotonic_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000LL + ts.tv_nsec;
}

}  // namespace tsmh::master_devices
