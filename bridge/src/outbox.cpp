#include "bridge/outbox.hpp"

#include <lcm/lcm-cpp.hpp>
#include <limits>

namespace tsmh::bridge {

OutboxStats OutboxBase::stats() const noexcept {
  OutboxStats s;
  s.queued = queued_.load(std::memory_order_relaxed);
  s.dropped_full = dropped_full_.load(std::memory_order_relaxed);
  s.published = published_.load(std::memory_order_relaxed);
  s.publish_errors = publish_errors_.load(std::memory_order_relaxed);
  return s;
}

template <class Sample>
std::size_t Outbox<Sample>::flush(lcm::LCM& lcm) noexcept {
  std::size_t n = 0;
  while (queue_.pop(pending_)) {
    ++n;
    try {
      to_message(pending_, msg_);
      const int size = msg_.getEncodedSize();
      bytes_.resize(static_cast<std::size_t>(size));  // allocates only when a message grows
      if (msg_.encode(bytes_.data(), 0, size) != size ||
          lcm.publish(channel_, bytes_.data(), static_cast<unsigned int>(size)) != 0) {
        publish_errors_.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
    } catch (const std::exception&) {  // allocation failure: count, keep the thread alive
      publish_errors_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    published_.fetch_add(1, std::memory_order_relaxed);
  }
  return n;
}

template class Outbox<SlaveStateSample>;
template class Outbox<SlaveTruthSample>;
template class Outbox<MasterCommandSample>;
template class Outbox<HapticStatusSample>;
template class Outbox<MasterStateSample>;
template class Outbox<MasterForceSample>;

}  // namespace tsmh::bridge
