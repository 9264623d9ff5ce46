#pragma once
// The `lcm` driver: a master whose vendor driver runs in another process
// (see examples/external_master_adapter/) and talks to us over LCM:
//
//   adapter -> server   MASTER_STATE  (tsmh::master_state_t)  q, qd, buttons, status
//   server  -> adapter  MASTER_FORCE  (tsmh::master_force_t)  torque, enable
//
// One MASTER_FORCE answers every MASTER_STATE (newest torque, zero when
// disabled, faulted, or when the loop stopped writing), so the adapter's
// own watchdog sees forces stop when either side dies. An LCM thread does
// all the I/O; the loop exchanges values with it through lock-free cells.

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "config/field_reader.hpp"
#include "master_devices/clock.hpp"
#include "master_devices/driver_base.hpp"
#include "master_devices/lcm_message_auth.hpp"
#include "master_devices/registry.hpp"
#include "realtime/latest_value.hpp"

namespace lcm {
class LCM;
}

namespace tsmh::master_devices {

struct LcmSettings {
  /// "" = $LCM_DEFAULT_URL, else LCM's default. haptic-server sets it to its
  /// own link's URL when the settings name none. Read by the strict parser
  /// (lcmtypes/lcm_url.hpp): a bad one is a settings error.
  std::string url;
  std::string channel_prefix;  ///< per-arm prefix, e.g. "LEFT_" -> LEFT_MASTER_STATE
  std::size_t dof = 2;         ///< num_joints the adapter must send
  double nominal_rate_hz = 1000.0;
  JointArray peak_torque_nm{};
  JointArray continuous_torque_nm{};
  JointArray position_min_rad{};
  JointArray position_max_rad{};
  JointArray max_stiffness_nm_per_rad{};
  std::int64_t stale_timeout_ms = 50;    ///< kDisconnected when MASTER_STATE stops this long
  std::int64_t command_timeout_ms = 20;  ///< zero torque when write_torque() calls stop this long
  /// Not a YAML setting: given by the program (register_lcm_driver). Set:
  /// only MASTER_STATE that verifies is used, and MASTER_FORCE is signed.
  std::shared_ptr<LcmMessageAuth> auth;

  std::string state_channel() const { return channel_prefix + "MASTER_STATE"; }
  std::string force_channel() const { return channel_prefix + "MASTER_FORCE"; }
};

LcmSettings parse_lcm_settings(config::FieldReader& r);

class LcmDevice final : public DriverBase {
 public:
  /// Uses its own LCM instance from settings.url. `clock` stamps each
  /// MASTER_STATE's arrival and each torque command.
  explicit LcmDevice(LcmSettings settings, std::shared_ptr<const Clock> clock = monotonic_clock());
  /// Uses a given LCM instance (e.g. "memq://" shared with a test); this
  /// device's thread is then the one that handles it.
  LcmDevice(LcmSettings settings, std::shared_ptr<lcm::LCM> lcm,
            std::shared_ptr<const Clock> clock = monotonic_clock());
  ~LcmDevice() override;

  void open() override;
  void close() noexcept override;
  /// Readings older than stale_timeout_ms are stale.
  std::int64_t freshness_bound_ns() const noexcept override {
    return settings_.stale_timeout_ms * 1'000'000LL;
  }

  /// MASTER_STATE dropped before use: not authentic, not decodable (size,
  /// type, joint count: lcmtypes/message_decoder.hpp) or not plausible.
  std::uint64_t rejected_messages() const { return rejected_.load(); }
  /// As given (the URL unresolved: "" means $LCM_DEFAULT_URL, else LCM's default).
  const LcmSettings& settings() const noexcept { return settings_; }
  /// Why the last one was dropped, naming the channel ("" if none was).
  std::string last_rejection() const;

  struct Impl;  // the LCM side (internal)

 private:
  friend struct Impl;

  LcmSettings settings_;
  std::shared_ptr<lcm::LCM> lcm_;
  std::unique_ptr<Impl> impl_;

  realtime::LatestValueReader<Command> command_reader_{commands_};  // the I/O thread's
  std::atomic<std::uint64_t> rejected_{0};
  std::atomic<bool> stopping_{false};
  std::thread thread_;
  std::string last_rejection_;  // guarded by error_mutex_
};

/// Registers the `lcm` driver; its devices read `clock`, and authenticate
/// their messages with `auth` when given (haptic-server passes the link key's).
void register_lcm_driver(DriverRegistry& registry,
                         std::shared_ptr<const Clock> clock = monotonic_clock(),
                         std::shared_ptr<LcmMessageAuth> auth = nullptr);

}  // namespace tsmh::master_devices
