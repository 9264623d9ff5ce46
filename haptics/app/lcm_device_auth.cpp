#include "lcm_device_auth.hpp"

#include <cstdio>
#include <string>

#include "realtime/clock.hpp"

namespace tsmh::haptics {
namespace {

using master_devices::LcmAuthResult;

class BridgeLcmAuth final : public master_devices::LcmMessageAuth, public LcmDeviceSessionView {
 public:
  explicit BridgeLcmAuth(std::shared_ptr<const bridge::LinkKey> key)
      : signer_(key), verifier_(std::move(key)), session_(signer_) {}

  LcmAuthResult verify(const std::string& channel, const std::uint8_t* data, std::size_t size,
                       std::string& why) noexcept override {
    const bridge::AuthResult r =
        verifier_.verify(channel, data, size, realtime::wall_clock_utime());
    switch (r.verdict) {
      case bridge::AuthVerdict::kOk:
        return judge(r, why);
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
    return {};
  }
  std::size_t trailer_size() const noexcept override { return bridge::kAuthTrailerBytes; }
  void sign(const std::string& channel, const std::uint8_t* payload, std::size_t size,
            std::uint8_t* trailer) noexcept override {
    signer_.sign(channel, payload, size, trailer);
  }
  void close_session() noexcept override { session_.close(); }
  const bridge::LinkSession& session() const noexcept override { return session_; }

 private:
  // One master session (bridge/link_session.hpp): only the bound adapter's
  // MASTER_STATE is used; another keyed master ends the session.
  LcmAuthResult judge(const bridge::AuthResult& r, std::string& why) {
    using Verdict = LcmAuthResult::Verdict;
    switch (session_.observe(r.trailer, realtime::monotonic_now_ns())) {
      case bridge::SessionVerdict::kAccept:
        return {Verdict::kUse, r.payload_size};
      case bridge::SessionVerdict::kHandshake:
        return {Verdict::kHandshake, r.payload_size};
      case bridge::SessionVerdict::kOtherSession: {
        char text[160];
        std::snprintf(text, sizeof text,
                      "another master session: sender %016llx naming %016llx (a second keyed "
                      "master, a restarted one or a replay): the session ends in FAULT",
                      static_cast<unsigned long long>(r.trailer.sender_id),
                      static_cast<unsigned long long>(r.trailer.peer_id));
        why = text;
        return {Verdict::kOtherSession, 0};
      }
      case bridge::SessionVerdict::kEnded:
        why = "the master session has ended";
        return {};
    }
    return {};
  }

  bridge::MessageSigner signer_;
  bridge::MessageVerifier verifier_;
  bridge::LinkSession session_;  // the server does not re-arm: a new master, a new server
};

}  // namespace

std::shared_ptr<master_devices::LcmMessageAuth> make_lcm_device_auth(
    std::shared_ptr<const bridge::LinkKey> key) {
  if (!key) return nullptr;
  return std::make_shared<BridgeLcmAuth>(std::move(key));
}

}  // namespace tsmh::haptics
