#pragma once
// Receiver: one LCM instance and one receive thread that keeps every
// subscribed channel's newest valid sample in its Inbox.
//
// The thread sleeps in poll() on LCM's file descriptor and, whenever it is
// readable, handles messages until none is pending, so LCM's per-subscription
// queue never fills (LCM drops the *newest* message when it is full). Each
// raw message goes to Inbox::ingest with the CLOCK_MONOTONIC time it was
// taken. Typical use (haptic server, one arm):
//
//   Receiver rx({.url = resolve_lcm_url(cli_url), .prefix = "ARM1_"});
//   auto& slave = rx.subscribe<SlaveStateSample>({.expected_joints = 2});
//   rx.start();
//   ... in the loop: SlaveStateSample s; if (slave.latest(s)) age = now - s.receive_ns;

#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#include "bridge/codec.hpp"
#include "bridge/inbox.hpp"
#include "bridge/lcm_url.hpp"
#include "bridge/link_auth.hpp"

namespace tsmh::bridge {

class Receiver {
 public:
  /// Opens LCM at config.url (throws BridgeError with a fix when it cannot).
  /// With config.key every inbox accepts only messages signed with that key,
  /// fresh (not for file://: a log is replayed later by design) and not
  /// replayed; without, a trailer found on a message is ignored.
  explicit Receiver(BridgeConfig config);
  ~Receiver();
  Receiver(const Receiver&) = delete;
  Receiver& operator=(const Receiver&) = delete;

  /// Adds an inbox for Sample's channel (config prefix + base name unless
  /// options.channel is set). Only before start(). The reference stays valid
  /// for the Receiver's lifetime.
  template <class Sample>
  Inbox<Sample>& subscribe(InboxOptions<Sample> options = {}) {
    std::string name = sample_channel<Sample>(config_.prefix, options.channel);
    auto inbox = std::make_unique<Inbox<Sample>>(std::move(name), std::move(options));
    Inbox<Sample>& ref = *inbox;
    add(std::move(inbox));
    return ref;
  }

  /// Starts the receive thread. Throws std::logic_error if already started.
  void start();
  /// Stops and joins the receive thread (also done by the destructor).
  void stop() noexcept;
  bool running() const noexcept { return thread_.joinable(); }

  const BridgeConfig& config() const noexcept { return config_; }
  /// For a udpm URL with ttl=0: how many of LCM's receive sockets start()
  /// restricted to datagrams from this host (bridge/host_only.hpp); 0 for
  /// other URLs.
  int host_only_sockets() const noexcept { return host_only_sockets_; }
  /// lcm handle() failures seen by the receive thread (should stay 0).
  std::uint64_t transport_errors() const noexcept {
    return transport_errors_.load(std::memory_order_relaxed);
  }

 private:
  /// What LCM's callback needs for one channel.
  struct Route {
    InboxBase* inbox;
    MessageVerifier* verifier;  // null: unauthenticated
  };

  static void on_raw_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                             Route* route);
  void add(std::unique_ptr<InboxBase> inbox);
  void run() noexcept;
  void back_off() noexcept;

  BridgeConfig config_;
  std::unique_ptr<lcm::LCM> lcm_;
  // One replay window per sender for all channels: a Sender numbers its
  // messages across its channels.
  std::unique_ptr<MessageVerifier> verifier_;
  std::vector<std::unique_ptr<InboxBase>> inboxes_;
  std::vector<std::unique_ptr<Route>> routes_;
  std::vector<LinkSession*> sessions_;  // distinct sessions of the inboxes, ticked by run()
  int lcm_fd_ = -1;
  int host_only_sockets_ = 0;
  int wake_fd_ = -1;  // eventfd: stop() wakes the thread out of poll()
  std::atomic<bool> stop_requested_{false};
  std::atomic<std::uint64_t> transport_errors_{0};
  std::thread thread_;
};

}  // namespace tsmh::bridge
