#pragma once
// The `sim` driver: a master console with a simulated operator's hand on it
// (simulated_operator.hpp). This is what the demo uses, and what makes the
// server loop testable without hardware.
//
// time: real       a thread integrates the hand at rate_hz on absolute
//                  deadlines, like a hardware device; read()/write_torque()
//                  exchange values with it through lock-free cells.
// time: simulated  no thread: read(now_ns) integrates the hand up to now_ns
//                  with the newest torque, so a loop that runs faster than
//                  real time (or single-steps in a test) stays
//                  deterministic. read() and write_torque() must then be
//                  called from the same thread.
//
// In real time the thread is paced by CLOCK_MONOTONIC, but readings and
// commands are stamped with the clock given to the constructor, so a test
// can age them with a ManualClock instead of sleeping.

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>

#include "config/field_reader.hpp"
#include "master_devices/clock.hpp"
#include "master_devices/driver_base.hpp"
#include "master_devices/simulated_operator.hpp"
#include "realtime/latest_value.hpp"

namespace tsmh::master_devices {

struct SimSettings {
  bool simulated_time = false;
  double rate_hz = 1000.0;
  std::size_t dof = 2;
  Scenario scenario = PalpateScenario{};
  HandParams hand;
  HandleParams handle;
  JointArray peak_torque_nm{0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3, 0.3};
  JointArray continuous_torque_nm{0.15, 0.15, 0.15, 0.15, 0.15, 0.15, 0.15, 0.15};
  JointArray position_min_rad{-1, -1, -1, -1, -1, -1, -1, -1};
  JointArray position_max_rad{1, 1, 1, 1, 1, 1, 1, 1};
  JointArray max_stiffness_nm_per_rad{5, 5, 5, 5, 5, 5, 5, 5};
  double encoder_resolution_rad = 0.0;   ///< quantize q like an encoder (0: exact)
  std::int64_t command_timeout_ms = 20;  ///< real time: zero torque when commands stop
  std::int64_t stale_timeout_ms = 20;    ///< real time: kDisconnected when readings stop
  Buttons buttons{true, false, false};   ///< held throughout (dead-man pressed by default)
};

/// Parses a `sim` settings map; every error names source and field.
SimSettings parse_sim_settings(config::FieldReader& r);

class SimDevice final : public DriverBase {
 public:
  explicit SimDevice(SimSettings settings, std::shared_ptr<const Clock> clock = monotonic_clock());
  ~SimDevice() override;

  void open() override;
  void close() noexcept override;
  /// In simulated time, first advances the world to now_ns.
  DeviceReading read(std::int64_t now_ns) noexcept override;
  /// stale_timeout_ms; in simulated time read() has just advanced the world
  /// to now_ns, so a reading is never stale.
  std::int64_t freshness_bound_ns() const noexcept override;
  bool simulated_time() const noexcept override { return settings_.simulated_time; }

  const SimSettings& settings() const { return settings_; }
  /// Scenario time, s (simulated-time mode: of the last read()).
  double scenario_time_s() const { return scenario_t_.load(); }

 private:
  void advance(double dt_s, std::int64_t t_ns) noexcept;  // integrate + publish
  void run_real_time();

  SimSettings settings_;
  SimulatedOperator operator_;
  realtime::LatestValueReader<Command> command_reader_{commands_};  // the I/O thread's
  std::atomic<double> scenario_t_{0.0};
  std::uint64_t count_ = 0;
  std::int64_t last_t_ns_ = 0;  // simulated time: time the hand has been integrated to
  bool started_ = false;
  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace tsmh::master_devices
