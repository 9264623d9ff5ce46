#include "master_devices/device_clock.hpp"

#include <algorithm>

namespace tsmh::master_devices {

namespace {
// A device step this far beyond the host's elapsed time is no drift but a
// clock that jumped (backwards shows as a step of almost 2^32 us).
constexpr std::int64_t kJumpSlackNs = 1'000'000'000;
}  // namespace

DeviceClock::Sample DeviceClock::start(std::uint32_t device_time_us,
                                       std::int64_t arrival_ns) noexcept {
  have_ = true;
  last_device_us_ = device_time_us;
  device_ns_ = 0;
  last_arrival_ns_ = arrival_ns;
  offset_ns_ = arrival_ns;  // device time counts from this sample
  return Sample{arrival_ns, 0, true};
}

DeviceClock::Sample DeviceClock::map(std::uint32_t device_time_us,
                                     std::int64_t arrival_ns) noexcept {
  if (!have_) return start(device_time_us, arrival_ns);
  const std::int64_t host_step_ns = std::max<std::int64_t>(0, arrival_ns - last_arrival_ns_);
  // Unsigned difference: correct across the u32 wrap.
  const auto step_us = static_cast<std::uint32_t>(device_time_us - last_device_us_);
  const std::int64_t step_ns = static_cast<std::int64_t>(step_us) * 1000;
  if (step_ns > host_step_ns + kJumpSlackNs) return start(device_time_us, arrival_ns);

  last_device_us_ = device_time_us;
  last_arrival_ns_ = arrival_ns;
  device_ns_ += step_ns;
  const std::int64_t sample_offset = arrival_ns - device_ns_;
  const auto allowance =
      static_cast<std::int64_t>(static_cast<double>(host_step_ns) * tolerance_ppm_ * 1e-6);
  offset_ns_ = std::min(offset_ns_ + allowance, sample_offset);
  const std::int64_t t = device_ns_ + offset_ns_;
  return Sample{t, arrival_ns - t, false};
}

}  // namespace tsmh::master_devices
