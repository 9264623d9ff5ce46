#pragma once
// What a standalone node (bridge/node_link.hpp) does with each raw LCM buffer
// of a message type it subscribes to, in the one safe order: verify the MAC
// (with a key), let the node's session decide whether the sender is its bound
// peer, then decode with the project's checked decoder (header, type hash,
// joint count and exact size before anything is allocated). Nothing is ever
// decoded by hand or by lcm-gen's decode() alone. Programs built on the
// bridge's Receiver get the same from their Inbox.

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string_view>

#include "bridge/link_auth.hpp"
#include "bridge/link_session.hpp"
#include "bridge/node_link.hpp"
#include "lcmtypes/message_decoder.hpp"
#include "realtime/clock.hpp"

namespace tsmh::bridge {

template <class Message>
class NodeInbox {
 public:
  /// `joints`: the joint count every accepted message must carry. Uses the
  /// link's verifier and session (none: an unauthenticated link).
  NodeInbox(const NodeLink& link, std::int32_t joints)
      : verifier_(link.verifier.get()), session_(link.session.get()), decoder_({joints, joints}) {}

  /// The decoded message, or null when the buffer is not to be used: not
  /// authentic (no MAC, wrong key, stale or replayed), part of the session's
  /// handshake, from another session (which the session has put in FAULT), or
  /// refused by the decoder (counted as rejected, with the reason). The
  /// message stays valid until the next call. No allocation.
  const Message* receive(const void* data, std::size_t size, std::string_view channel) {
    const auto* bytes = static_cast<const std::uint8_t*>(data);
    if (verifier_ != nullptr) {
      const auto auth = verifier_->verify(channel, bytes, size, realtime::wall_clock_utime());
      if (auth.verdict != AuthVerdict::kOk) {
        ++unauthentic_;
        return nullptr;
      }
      switch (session_->observe(auth.trailer, realtime::monotonic_now_ns())) {
        case SessionVerdict::kAccept:
          break;
        case SessionVerdict::kHandshake:
        case SessionVerdict::kEnded:
          return nullptr;
        case SessionVerdict::kOtherSession:
          ++other_session_;
          return nullptr;
      }
      size = auth.payload_size;
    }
    // Without a key, another peer's MAC trailer is left unread (as by every
    // LCM tool); with one, the verified payload must be exactly the message.
    const auto trailing =
        verifier_ != nullptr ? lcmtypes::Trailing::kReject : lcmtypes::Trailing::kIgnore;
    if (const auto error = decoder_.decode(bytes, size, trailing)) {
      reject(error->what.data());
      return nullptr;
    }
    return &decoder_.message();
  }

  /// Counts a message the node's own checks refused after decoding (a NaN,
  /// an old sequence number) and keeps why, for the node's summary.
  void reject(const char* why) noexcept {
    ++rejected_;
    std::snprintf(last_rejection_.data(), last_rejection_.size(), "%s", why);
  }

  std::int64_t unauthentic() const noexcept { return unauthentic_; }
  /// Keyed messages of another session.
  std::int64_t other_session() const noexcept { return other_session_; }
  std::int64_t rejected() const noexcept { return rejected_; }
  /// Why the last message was rejected; empty when none was.
  const char* last_rejection() const noexcept { return last_rejection_.data(); }

 private:
  MessageVerifier* verifier_;
  LinkSession* session_;
  lcmtypes::MessageDecoder<Message> decoder_;
  std::int64_t unauthentic_ = 0;
  std::int64_t other_session_ = 0;
  std::int64_t rejected_ = 0;
  std::array<char, 96> last_rejection_{};
};

}  // namespace tsmh::bridge
