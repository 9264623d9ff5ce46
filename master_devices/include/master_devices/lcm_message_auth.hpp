#pragma once
// Authentication of the `lcm` driver's messages (MASTER_STATE in,
// MASTER_FORCE out), supplied by the program that builds the registry:
// master_devices depends on no crypto and no bridge; haptic-server plugs in
// the bridge's link key (docs/bridge.md, "Authentication"). verify() is
// called from the device's LCM thread only; sign() also from the program's
// main thread (haptic-server prepares its crash MASTER_FORCE with it), so an
// implementation's sign() must be thread-safe.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

namespace tsmh::master_devices {

class LcmMessageAuth {
 public:
  virtual ~LcmMessageAuth() = default;
  /// The payload size of an authentic message on `channel` (the bytes before
  /// its trailer), or nullopt with `why` set: the message is dropped and
  /// counted, never decoded.
  virtual std::optional<std::size_t> verify(const std::string& channel, const std::uint8_t* data,
                                            std::size_t size, std::string& why) noexcept = 0;
  /// Bytes sign() appends after a payload.
  virtual std::size_t trailer_size() const noexcept = 0;
  /// Writes the trailer of `payload` published on `channel` to trailer[0..trailer_size()).
  virtual void sign(const std::string& channel, const std::uint8_t* payload, std::size_t size,
                    std::uint8_t* trailer) noexcept = 0;
};

}  // namespace tsmh::master_devices
