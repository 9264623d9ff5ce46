#pragma once
// The link key's authentication for the `lcm` master driver: the bridge's
// MessageSigner / MessageVerifier behind master_devices' LcmMessageAuth, so
// MASTER_STATE and MASTER_FORCE carry the same MAC trailer as every bridge
// channel (docs/bridge.md, "Authentication").

#include <memory>

#include "bridge/link_auth.hpp"
#include "master_devices/lcm_message_auth.hpp"

namespace tsmh::haptics {

/// Null when `key` is null (unauthenticated link).
std::shared_ptr<master_devices::LcmMessageAuth> make_lcm_device_auth(
    std::shared_ptr<const bridge::LinkKey> key);

}  // namespace tsmh::haptics
