#pragma once
// The test side of a keyed session (bridge/link_session.hpp): a test that
// plays the slave or the master console signs what it publishes with a
// MessageSigner; SessionAnswer listens to the other side's channel (raw,
// verified with the same key) and keeps that signer's peer id on the
// session, as a real slave or adapter does, so the server binds to it.

#include <atomic>
#include <lcm/lcm-cpp.hpp>
#include <memory>
#include <string>
#include <thread>

#include "bridge/link_auth.hpp"
#include "bridge/link_session.hpp"
#include "realtime/clock.hpp"

namespace tsmh::haptics::test {

class SessionAnswer {
 public:
  /// Answers for `signer` the sessions of whoever publishes on `channel` (the
  /// server's MASTER_COMMAND or MASTER_FORCE). Null key or signer: nothing to do.
  SessionAnswer(const std::string& url, const std::string& channel,
                std::shared_ptr<const bridge::LinkKey> key, bridge::MessageSigner* signer)
      : lcm_(url) {
    if (!key || signer == nullptr) return;
    verifier_ = std::make_unique<bridge::MessageVerifier>(std::move(key));
    session_ =
        std::make_unique<bridge::LinkSession>(*signer, bridge::SessionOptions{.rearm = true});
    lcm_.subscribeFunction<SessionAnswer*>(
        channel,
        [](const lcm::ReceiveBuffer* rb, const std::string& ch, SessionAnswer* self) {
          const auto r = self->verifier_->verify(ch, static_cast<const std::uint8_t*>(rb->data),
                                                 rb->data_size, realtime::wall_clock_utime());
          if (r.verdict == bridge::AuthVerdict::kOk)
            self->session_->observe(r.trailer, realtime::monotonic_now_ns());
        },
        this);
    thread_ = std::thread([this] {
      while (running_)
        lcm_.handleTimeout(10);
    });
  }
  ~SessionAnswer() {
    running_ = false;
    if (thread_.joinable()) thread_.join();
  }
  SessionAnswer(const SessionAnswer&) = delete;
  SessionAnswer& operator=(const SessionAnswer&) = delete;

  /// Null when unkeyed.
  const bridge::LinkSession* session() const { return session_.get(); }

 private:
  lcm::LCM lcm_;
  std::unique_ptr<bridge::MessageVerifier> verifier_;
  std::unique_ptr<bridge::LinkSession> session_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

}  // namespace tsmh::haptics::test
