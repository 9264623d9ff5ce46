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

/// What to do with one incoming MASTER_STATE.
struct LcmAuthResult {
  enum class Verdict : std::uint8_t {
    kUse,           ///< authentic, from the session's peer: decode and use it
    kHandshake,     ///< authentic, part of binding the session: answer (zero force), do not use
    kRefuse,        ///< not authentic (or the session is over): drop, count, say why
    kOtherSession,  ///< authentic but another master: the session ends, the device faults
  };
  Verdict verdict = Verdict::kRefuse;
  std::size_t payload_size = 0;  ///< the bytes before the trailer (kUse, kHandshake)
};

class LcmMessageAuth {
 public:
  virtual ~LcmMessageAuth() = default;
  /// Judges a message on `channel`; `why` is set when it is refused or ends
  /// the session. A refused message is dropped and counted, never decoded.
  virtual LcmAuthResult verify(const std::string& channel, const std::uint8_t* data,
                               std::size_t size, std::string& why) noexcept = 0;
  /// Bytes sign() appends after a payload.
  virtual std::size_t trailer_size() const noexcept = 0;
  /// Writes the trailer of `payload` published on `channel` to trailer[0..trailer_size()).
  virtual void sign(const std::string& channel, const std::uint8_t* payload, std::size_t size,
                    std::uint8_t* trailer) noexcept = 0;
  /// Every message signed after this says goodbye: the peer's session ends
  /// at once (a clean stop) instead of after its timeout.
  virtual void close_session() noexcept {}
};

}  // namespace tsmh::master_devices
