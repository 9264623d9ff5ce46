#pragma once
// Sender: one LCM instance and one publish thread serving any number of
// Outboxes. Typical use (virtual slave node):
//
//   Sender tx({.url = resolve_lcm_url(cli_url), .prefix = prefix});
//   auto& state = tx.outbox<SlaveStateSample>();
//   auto& truth = tx.outbox<SlaveTruthSample>();
//   tx.start();
//   ... each tick: s.utime = realtime::monotonic_utime(); s.seq = tick; state.publish(s);

#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "bridge/lcm_url.hpp"
#include "bridge/outbox.hpp"

namespace tsmh::bridge {

struct SenderOptions {
  /// How the publish thread learns about new samples (docs/bridge.md has the
  /// measurements behind the default):
  ///  0   Outbox::publish() wakes it (a futex wake: ~1-10 us in the caller,
  ///      lowest latency);
  ///  > 0 it wakes every poll_period and Outbox::publish() is a plain copy
  ///      into the ring with no system call; adds up to poll_period latency.
  std::chrono::microseconds poll_period{0};
};

class Sender {
 public:
  /// Opens LCM at config.url (throws BridgeError with a fix when it cannot).
  /// With config.key every message carries an authentication trailer.
  explicit Sender(BridgeConfig config, SenderOptions options = {});
  ~Sender();
  Sender(const Sender&) = delete;
  Sender& operator=(const Sender&) = delete;

  /// Adds an outbox for Sample's channel (prefix + base name, or `channel`
  /// when non-empty). Only before start(); the reference stays valid for the
  /// Sender's lifetime.
  template <class Sample>
  Outbox<Sample>& outbox(std::string channel = {}) {
    auto box = std::make_unique<Outbox<Sample>>(
        sample_channel<Sample>(config_.prefix, std::move(channel)), signal_);
    Outbox<Sample>& ref = *box;
    add(std::move(box));
    return ref;
  }

  /// Starts the publish thread. Throws std::logic_error if already started.
  void start();
  /// Publishes what is still queued, then stops and joins (also done by the destructor).
  void stop() noexcept;
  bool running() const noexcept { return thread_.joinable(); }

  const BridgeConfig& config() const noexcept { return config_; }
  /// The underlying LCM instance, for synchronous publish_sample() from
  /// non-real-time code (LCM's publish is thread-safe); pass signer() along
  /// so those messages are authenticated too.
  lcm::LCM& lcm() noexcept { return *lcm_; }
  /// Signs this Sender's messages (config.key); null when unauthenticated.
  MessageSigner* signer() noexcept { return signer_.get(); }

 private:
  void add(std::unique_ptr<OutboxBase> box);
  void run() noexcept;

  BridgeConfig config_;
  SenderOptions options_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<MessageSigner> signer_;
  std::vector<std::unique_ptr<OutboxBase>> outboxes_;
  PublishSignal signal_;
  std::atomic<bool> stop_requested_{false};
  std::thread thread_;
};

}  // namespace tsmh::bridge
