#include "bridge/sender.hpp"

#include <algorithm>
#include <ctime>
#include <lcm/lcm-cpp.hpp>
#include <stdexcept>

#include "realtime/clock.hpp"
#include "realtime/pacing.hpp"

namespace tsmh::bridge {

Sender::Sender(BridgeConfig config, SenderOptions options)
    : config_(std::move(config)),
      options_(options),
      lcm_(open_lcm(config_.url)),
      signer_(config_.key ? std::make_unique<MessageSigner>(config_.key) : nullptr),
      signal_(/*wake_on_publish=*/options.poll_period.count() <= 0) {}

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
  signal_.force();
  thread_.join();
}

void Sender::run() noexcept {
  const std::int64_t period_ns = options_.poll_period.count() * 1000;
  realtime::Pacer pace(std::max<std::int64_t>(period_ns, 1),
                       realtime::monotonic_now_ns() + period_ns);
  for (;;) {
    const std::uint32_t seen = signal_.current();
    for (auto& box : outboxes_)
      box->flush(*lcm_, signer_.get());
    if (stop_requested_.load(std::memory_order_acquire)) {
      for (auto& box : outboxes_)
        box->flush(*lcm_, signer_.get());  // what was pushed before stop()
      return;
    }
    if (period_ns <= 0) {
      signal_.wait_change(seen);
      continue;
    }
    // Polling: absolute deadlines; after a stall, re-base instead of catching up.
    pace.wait();  // a signal's early wake-up only flushes early
    pace.advance(realtime::monotonic_now_ns());
  }
}

}  // namespace tsmh::bridge
