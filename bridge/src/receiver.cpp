#include "bridge/receiver.hpp"

#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

#include "bridge/host_only.hpp"
#include "realtime/clock.hpp"

namespace tsmh::bridge {
namespace {

bool is_log_url(const std::string& url) {
  return url.rfind("file://", 0) == 0;
}

}  // namespace

// LCM's raw-subscription callback: authenticate (keyed), then hand the payload
// to the inbox with the time it was taken off LCM's queue.
void Receiver::on_raw_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel,
                              Route* route) {
  InboxBase* inbox = route->inbox;
  if (inbox->discarding()) return inbox->count_discarded();
  const std::int64_t receive_ns = realtime::monotonic_now_ns();
  const auto* data = static_cast<const std::uint8_t*>(rbuf->data);
  std::size_t size = rbuf->data_size;
  if (route->verifier != nullptr) {
    const AuthResult auth =
        route->verifier->verify(channel, data, size, realtime::wall_clock_utime());
    if (auth.verdict != AuthVerdict::kOk) return inbox->reject_unauthentic(auth, receive_ns);
    // One master, one slave: on a session channel only the bound peer's
    // messages go on (bridge/link_session.hpp); another keyed sender ends it.
    if (LinkSession* session = inbox->session()) {
      const SessionVerdict v = session->observe(auth.trailer, receive_ns);
      if (v != SessionVerdict::kAccept)
        return inbox->refuse_by_session(v, auth.trailer, receive_ns);
    }
    size = auth.payload_size;
  } else {
    size -= auth_trailer_size(
        data, size);  // an unkeyed reader (a test, a tool) still decodes signed traffic
  }
  inbox->ingest(data, size, receive_ns);
}

Receiver::Receiver(BridgeConfig config) : config_(std::move(config)), lcm_(open_lcm(config_.url)) {
  if (config_.key)
    verifier_ = std::make_unique<MessageVerifier>(
        config_.key, VerifierOptions{.check_freshness = !is_log_url(config_.url),
                                     .accept_version_1 = is_log_url(config_.url)});
  wake_fd_ = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (wake_fd_ < 0)
    throw BridgeError(std::string("Receiver: eventfd failed: ") + std::strerror(errno));
}

Receiver::~Receiver() {
  stop();
  if (wake_fd_ >= 0) close(wake_fd_);
}

void Receiver::add(std::unique_ptr<InboxBase> inbox) {
  if (running()) throw std::logic_error("Receiver::subscribe after start(): " + inbox->channel());
  check_channel_name(inbox->channel());
  routes_.push_back(std::make_unique<Route>(Route{inbox.get(), verifier_.get()}));
  if (LinkSession* s = inbox->session();
      s != nullptr && std::find(sessions_.begin(), sessions_.end(), s) == sessions_.end())
    sessions_.push_back(s);
  lcm::Subscription* sub = lcm_->subscribeFunction<Route*>(regex_escape(inbox->channel()),
                                                           &on_raw_message, routes_.back().get());
  if (sub == nullptr) throw BridgeError("Receiver: cannot subscribe to " + inbox->channel());
  // We drain continuously, so the queue only has to absorb a scheduling
  // hiccup of the receive thread; it is not what keeps the newest sample.
  sub->setQueueCapacity(256);
  inboxes_.push_back(std::move(inbox));
}

void Receiver::start() {
  if (running()) throw std::logic_error("Receiver::start: already running");
  // LCM's udpm provider joins the multicast group lazily; asking for the
  // descriptor here makes sure that messages sent after start() returns are heard.
  lcm_fd_ = lcm_->getFileno();
  if (lcm_fd_ < 0) throw BridgeError("Receiver: LCM has no file descriptor for " + config_.url);
  // ttl=0 promises "this host": make it true for receiving too (LCM's socket
  // listens on every interface). Fail closed: a ttl=0 link that would hear
  // other hosts is an error, not a warning.
  if (const auto port = host_only_udpm_port(config_.url)) {
    host_only_sockets_ = restrict_udp_port_to_host(*port);
    if (host_only_sockets_ == 0)
      throw BridgeError("Receiver: cannot restrict LCM's socket for '" + config_.url +
                        "' to this host (no UDP socket on port " + std::to_string(*port) +
                        " found, or SO_ATTACH_FILTER refused); use a ttl other than 0 for a "
                        "network link, with the link key");
  }
  // LCM has been receiving since subscribe(): whatever queued up meanwhile
  // (up to each subscription's queue capacity; the rest LCM dropped) is as old
  // as the time between subscribe() and now. Drop it, counted, so the first
  // sample the loop sees is a fresh one and the statistics describe the link,
  // not our start-up (a 480 MB trace allocation once made that 1.3 s: p99
  // latency 1.18 s and ~1050 sequence numbers "missing" in every demo).
  // Only a network provider: a file:// log is data to replay, not a backlog.
  if (config_.url.rfind("udpm://", 0) == 0) {
    for (auto& inbox : inboxes_)
      inbox->set_discarding(true);
    for (int i = 0; i < 1'000'000 && lcm_->handleTimeout(0) > 0; ++i) {
    }
    for (auto& inbox : inboxes_)
      inbox->set_discarding(false);
  }
  stop_requested_.store(false, std::memory_order_relaxed);
  thread_ = std::thread([this] { run(); });
}

void Receiver::stop() noexcept {
  if (!running()) return;
  stop_requested_.store(true, std::memory_order_relaxed);
  const std::uint64_t one = 1;
  [[maybe_unused]] const ssize_t n = write(wake_fd_, &one, sizeof one);
  thread_.join();
  std::uint64_t drained = 0;
  [[maybe_unused]] const ssize_t m = read(wake_fd_, &drained, sizeof drained);
}

void Receiver::back_off() noexcept {
  // Counted, then 100 ms of quiet (still woken by stop()) instead of spinning
  // on a descriptor that keeps failing.
  transport_errors_.fetch_add(1, std::memory_order_relaxed);
  pollfd wake{wake_fd_, POLLIN, 0};
  poll(&wake, 1, 100);
}

void Receiver::run() noexcept {
  const int lcm_fd = lcm_fd_;
  // Sessions need a look even when nothing arrives (a silent peer).
  const int timeout_ms = sessions_.empty() ? -1 : 100;
  while (!stop_requested_.load(std::memory_order_relaxed)) {
    pollfd fds[2] = {{lcm_fd, POLLIN, 0}, {wake_fd_, POLLIN, 0}};
    const int ready = poll(fds, 2, timeout_ms);
    if (!sessions_.empty()) {
      const std::int64_t now = realtime::monotonic_now_ns();
      for (LinkSession* s : sessions_)
        s->tick(now);
    }
    if (ready < 0) {
      if (errno != EINTR) back_off();
      continue;
    }
    if ((fds[0].revents & (POLLERR | POLLHUP | POLLNVAL)) != 0 && (fds[0].revents & POLLIN) == 0) {
      // LCM's descriptor is broken (e.g. a file:// provider at its end):
      // count it and back off instead of spinning, still waking on stop().
      back_off();
      continue;
    }
    if ((fds[0].revents & POLLIN) == 0) continue;
    // Handle everything pending before sleeping again: LCM's queue must stay
    // empty so no newer message is ever dropped in favour of an older one.
    for (;;) {
      const int handled = lcm_->handleTimeout(0);
      if (handled > 0) continue;
      if (handled < 0) back_off();  // e.g. a file:// provider past the end of its log
      break;
    }
  }
}

}  // namespace tsmh::bridge
