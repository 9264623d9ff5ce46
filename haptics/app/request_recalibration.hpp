#pragma once
// haptic-server --request-recalibration: the "external console" side of the
// recalibration as a one-shot command: sends one CALIBRATION_REQUEST for every
// joint of the configuration to the server running with it, and exits.
// The outcome is in that server's log and HAPTIC_STATUS.

#include <cstdio>
#include <optional>
#include <string>

#include "bridge/channels.hpp"
#include "bridge/lcm_url.hpp"
#include "bridge/link_security.hpp"
#include "bridge/sender.hpp"
#include "haptics/server_config.hpp"
#include "realtime/clock.hpp"

namespace tsmh::haptic_server {

inline int request_recalibration(const std::string& config_path, const std::string& lcm_url,
                                 const std::optional<std::string>& prefix,
                                 const bridge::LinkSecurityOptions& link) {
  const haptics::ServerConfig cfg = haptics::load_server_config(config_path);
  bridge::BridgeConfig b;
  b.url = bridge::resolve_lcm_url(lcm_url.empty() ? cfg.lcm_url : lcm_url);
  b.prefix = prefix ? *prefix : cfg.lcm_prefix;
  // Signed with the link key like everything the server accepts
  // (docs/bridge.md, "Authentication").
  b.key = bridge::resolve_link_security(b.url, link).key;
  bridge::Sender tx(b);
  auto& out = tx.outbox<bridge::CalibrationRequestSample>();
  tx.start();
  bridge::CalibrationRequestSample s;
  s.utime = realtime::monotonic_utime();
  s.seq = s.utime;  // advances from one request to the next, as receivers require
  s.num_joints = cfg.loop.joints;
  for (int j = 0; j < cfg.loop.joints; ++j)
    s.recalibrate[static_cast<std::size_t>(j)] = true;
  out.publish(s);
  tx.stop();  // publishes what is queued first
  std::fprintf(stderr,
               "haptic-server: CALIBRATION_REQUEST sent on '%s' (%d joints, %s): move the "
               "instrument in free space for %.1f s; the outcome is in the server's log and "
               "HAPTIC_STATUS\n",
               bridge::channel_name(b.prefix, bridge::Channel::kCalibrationRequest).c_str(),
               cfg.loop.joints, b.url.c_str(), cfg.loop.recalibration.collect_s);
  return 0;
}

}  // namespace tsmh::haptic_server
