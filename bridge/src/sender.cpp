#include "bridge/sender.hpp"

#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

namespace tsmh::bridge {

Sender::Sender(BridgeConfig config) : config_(std::move(config)), lcm_(open_lcm(config_.url)) {}

Sender::~Sender() {
  stop();
}

void Sender::add(std::unique_ptr<OutboxBase> box) {
  if (running()) throw std::logic_error("Sender::outbox after start(): " + box->channel());
  check_channel_name(box->channel());
  outboxes_.push_back(std::move(box));
}

void Sender::start() {
  if (running()) throw std::logic_error("Sender::start: already running");
  stop_requested_.store(false, std::memory_order_relaxed);
  thread_ = std::thread([this] { run(); });
}

void Sender::stop() noexcept {
  if (!running()) return;
  stop_requested_.store(true, std::memory_order_release);
  signal_.notify();
  thread_.join();
}

void Sender::run() noexcept {
  for (;;) {
    const std::uint32_t seen = signal_.current();
    for (auto& box : outboxes_)
      box->flush(*lcm_);
    if (stop_requested_.load(std::memory_order_acquire)) {
      for (auto& box : outboxes_)
        box->flush(*lcm_);  // what was pushed before stop()
      return;
    }
    signal_.wait_change(seen);
  }
}

}  // namespace tsmh::bridge
