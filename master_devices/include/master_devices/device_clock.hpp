#pragma once
// Maps the console's own clock (device_time_us in every input report) onto
// the host's CLOCK_MONOTONIC, so that a sample is dated when the device took
// it, not when the host happened to read it. A report the kernel queued and
// the driver read late (a starved host, the last reports before an unplug)
// then looks as old as it is, instead of fresh.
//
// Every report gives arrival = device_time + offset + delay with delay >= 0,
// so the smallest (arrival - device_time) seen is the best estimate of the
// offset (the transport's minimum latency folded in): a minimum filter,
// robust to any number of late reports. Clocks drift apart (the device's
// crystal, NTP slewing CLOCK_MONOTONIC): a device clock running faster than
// the host's lowers the minimum by itself; for one running slower, the
// estimate may rise by at most `tolerance_ppm` of the host time elapsed. A
// report's lateness is how much later it arrived than the estimate says it
// could have. A device clock that jumps backwards (or forwards by more than
// the host's elapsed time plus a second: a restarted firmware) restarts the
// estimate.
//
// Pure value type, no allocation: runs in the driver's I/O context.

#include <cstdint>

namespace tsmh::master_devices {

class DeviceClock {
 public:
  /// Largest rate difference between the device's clock and CLOCK_MONOTONIC
  /// the estimate follows (USB: full-speed devices +-2500 ppm, high-speed
  /// +-500 ppm; NTP slews CLOCK_MONOTONIC by up to 500 ppm).
  static constexpr double kDefaultTolerancePpm = 5000.0;

  explicit DeviceClock(double tolerance_ppm = kDefaultTolerancePpm) noexcept
      : tolerance_ppm_(tolerance_ppm) {}

  struct Sample {
    std::int64_t t_ns = 0;     ///< when the device took the sample, on CLOCK_MONOTONIC (<= arrival)
    std::int64_t late_ns = 0;  ///< arrival - t_ns: delivery delay beyond the minimum seen
    bool restarted = false;    ///< the estimate started over with this sample
  };

  /// One input report: its device time and its arrival on CLOCK_MONOTONIC.
  /// Arrivals must not go backwards (one I/O context stamps them).
  Sample map(std::uint32_t device_time_us, std::int64_t arrival_ns) noexcept;

  /// Forget everything (a new connection).
  void reset() noexcept { have_ = false; }

  bool started() const noexcept { return have_; }
  /// Current estimate of host time minus device time, ns.
  double tolerance_ppm() const noexcept { return tolerance_ppm_; }

 private:
  Sample start(std::uint32_t device_time_us, std::int64_t arrival_ns) noexcept;

  double tolerance_ppm_;
  bool have_ = false;
  std::uint32_t last_device_us_ = 0;
  std::int64_t device_ns_ = 0;  // device time unwrapped (the u32 wraps after ~71 min), ns
  std::int64_t last_arrival_ns_ = 0;
  std::int64_t offset_ns_ = 0;
};

}  // namespace tsmh::master_devices
