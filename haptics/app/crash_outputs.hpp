#pragma once
// haptic-server's messages for a crash (bridge/crash_stop.hpp; docs/haptic-server.md,
// "Crash"): what the handler sends when a core-dumping signal ends the
// process, prepared and kept fresh here by the main thread.
//
//   - to the slave: MASTER_COMMAND enable 0 (hold), as one udpm datagram on
//     the link's URL, signed like the link's own messages;
//   - `lcm` master driver: MASTER_FORCE enable 0, zero torque, on the
//     driver's URL, signed like the driver's own;
//   - `hid` console: an OUTPUT report with enable 0 and zero current, written
//     to a second descriptor on its hidraw node.
//
// A keyed receiver accepts a trailer only while its send time is within 2 s
// of its clock and its (sender, sequence) is new and within the replay
// window, so the signed datagrams are re-made every kRefreshNs with a
// sequence reserved from the same signer as the live stream and the current
// time. Their payload's utime and seq lie kLeadUs / kSeqLead ahead of the
// last command sent, so a receiver that orders by them (bridge inbox:
// seq up and utime up) takes the hold as the newest message whenever it
// comes within the trailer's freshness.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "bridge/crash_stop.hpp"
#include "haptics/lcm_slave_link.hpp"
#include "master_devices/device.hpp"
#include "master_devices/lcm_message_auth.hpp"

namespace tsmh::haptic_server {

class CrashOutputs {
 public:
  static constexpr std::int64_t kRefreshNs = 100'000'000;
  static constexpr std::int64_t kLeadUs = 2'000'000;  ///< the freshness window of a keyed receiver
  static constexpr std::int64_t kSeqLead = 10'000;    ///< > 2 s of commands at the 4 kHz limit

  struct Setup {
    haptics::LcmSlaveLink& link;
    std::string link_url;  ///< resolved
    int joints = 0;
    master_devices::Device& device;
    std::string driver;  ///< "lcm", "hid", ...
    /// The lcm driver's signer (null: unkeyed, or another driver).
    std::shared_ptr<master_devices::LcmMessageAuth> device_auth;
  };

  /// Creates the outputs, finds the senders to silence, prepares every
  /// message once and installs the handler. Call after the link started
  /// and the device opened (their sockets and descriptors exist then).
  explicit CrashOutputs(Setup setup);
  CrashOutputs(const CrashOutputs&) = delete;
  CrashOutputs& operator=(const CrashOutputs&) = delete;

  /// Main thread, at least every 50 ms: re-makes the signed messages every
  /// kRefreshNs, and follows a console that came back on another node and
  /// a Haply board whose port was opened again.
  void refresh(std::int64_t now_ns);

  /// What the handler would do, one line ("hold to the slave on ..., zero
  /// MASTER_FORCE on ..."), for the start-up log.
  const std::string& summary() const noexcept { return summary_; }

 private:
  void prepare_hold();
  void prepare_force();
  void follow_console();
  void follow_haply();
  void find_senders();

  Setup s_;
  bridge::CrashStop stop_;
  int hold_ = -1, force_ = -1, console_ = -1, haply_ = -1;
  int haply_fd_ = -1;       // the board's port descriptor the haply output copies
  std::string haply_node_;  // its port, so the driver's own descriptor is silenced
  std::string force_channel_;
  int force_dof_ = 0;
  int link_port_ = 0, device_port_ = 0;
  std::string console_node_;
  std::int64_t next_refresh_ns_ = 0;
  std::vector<std::uint8_t> payload_;
  std::vector<std::uint8_t> datagram_;
  std::string summary_;
};

}  // namespace tsmh::haptic_server
