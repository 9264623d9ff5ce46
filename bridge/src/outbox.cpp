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
std::size_t Outbox<Sample>::flush(lcm::LCM& lcm, MessageSigner* signer) noexcept {
  std::size_t n = 0;
  while (queue_.pop(pending_)) {
    ++n;
    try {
      to_message(pending_, msg_);
      const int size = msg_.getEncodedSize();
      const int trailer = signer != nullptr ? static_cast<int>(kAuthTrailerBytes) : 0;
      // allocates only when a message grows
      bytes_.resize(static_cast<std::size_t>(size) + static_cast<std::size_t>(trailer));
      if (msg_.encode(bytes_.data(), 0, size) != size) {
        publish_errors_.fetch_add(1, std::memory_order_relaxed);
        continue;
      }
      // Signed here, in the publish thread: the loop's publish() stays a copy.
      if (signer != nullptr)
        signer->sign(channel_, bytes_.data(), static_cast<std::size_t>(size), bytes_.data() + size);
      if (lcm.publish(channel_, bytes_.data(), static_cast<unsigned int>(size + trailer)) != 0) {
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
template class Outbox<CalibrationRequestSample>;

}  // namespace tsmh::bridge
