#include "lcm_device_auth.hpp"

#include <string>

#include "realtime/clock.hpp"

namespace tsmh::haptics {
namespace {

class BridgeLcmAuth final : public master_devices::LcmMessageAuth {
 public:
  explicit BridgeLcmAuth(std::shared_ptr<const bridge::LinkKey> key)
      : signer_(key), verifier_(std::move(key)) {}

  std::optional<std::size_t> verify(const std::string& channel, const std::uint8_t* data,
                                    std::size_t size, std::string& why) noexcept override {
    const bridge::AuthResult r =
        verifier_.verify(channel, data, size, realtime::wall_clock_utime());
    switch (r.verdict) {
      case bridge::AuthVerdict::kOk:
        return r.payload_size;
      case bridge::AuthVerdict::kMissing:
        why = "no MAC trailer (the sender has no link key)";
        break;
      case bridge::AuthVerdict::kVersion1:
        why = "trailer version 1 (a sender from before sessions: update it)";
        break;
      case bridge::AuthVerdict::kBadMac:
        why = "MAC does not match (wrong link key, or altered on the way)";
        break;
      case bridge::AuthVerdict::kStale:
        why = "sent " + std::to_string(r.age_us) + " us from this host's clock (a recording?)";
        break;
      case bridge::AuthVerdict::kReplayed:
        why = "replayed (sender and sequence already seen)";
        break;
    }
    return std::nullopt;
  }
  std::size_t trailer_size() const noexcept override { return bridge::kAuthTrailerBytes; }
  void sign(const std::string& channel, const std::uint8_t* payload, std::size_t size,
            std::uint8_t* trailer) noexcept override {
    signer_.sign(channel, payload, size, trailer);
  }

 private:
  bridge::MessageSigner signer_;
  bridge::MessageVerifier verifier_;
};

}  // namespace

std::shared_ptr<master_devices::LcmMessageAuth> make_lcm_device_auth(
    std::shared_ptr<const bridge::LinkKey> key) {
  if (!key) return nullptr;
  return std::make_shared<BridgeLcmAuth>(std::move(key));
}

}  // namespace tsmh::haptics
