#pragma once
// The link key's authentication for the `lcm` master driver: the bridge's
// MessageSigner / MessageVerifier / LinkSession behind master_devices'
// LcmMessageAuth, so MASTER_STATE and MASTER_FORCE carry the same MAC
// trailer as every bridge channel and the server listens to exactly one
// master session (docs/bridge.md, "Authentication" and "Sessions").

#include <memory>

#include "bridge/link_auth.hpp"
#include "bridge/link_session.hpp"
#include "master_devices/lcm_message_auth.hpp"

namespace tsmh::haptics {

/// The master link's session, for the server's status and summary.
class LcmDeviceSessionView {
 public:
  virtual ~LcmDeviceSessionView() = default;
  virtual const bridge::LinkSession& session() const noexcept = 0;
};

/// Null when `key` is null (unauthenticated link). The returned object is
/// also an LcmDeviceSessionView.
std::shared_ptr<master_devices::LcmMessageAuth> make_lcm_device_auth(
    std::shared_ptr<const bridge::LinkKey> key);

}  // namespace tsmh::haptics
