#pragma once
// SpscQueue<T, Capacity>: a bounded single-producer single-consumer ring of
// trivially copyable values. push() and pop() are wait-free and never
// allocate: the loop thread pushes outgoing messages, the publish thread pops
// them. When the ring is full push() fails instead of waiting (the caller
// counts the drop); a full ring means the publish thread is far behind, and
// the loop must not be slowed down by that.

#include <array>
#include <atomic>
#include <cstddef>
#include <type_traits>

namespace tsmh::bridge {

template <class T, std::size_t Capacity>
class SpscQueue {
  static_assert(std::is_trivially_copyable_v<T>);
  static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0, "Capacity: a power of two");

 public:
  SpscQueue() = default;
  SpscQueue(const SpscQueue&) = delete;
  SpscQueue& operator=(const SpscQueue&) = delete;

  /// Producer only. False when full (nothing is written).
  bool push(const T& value) noexcept {
    const std::size_t head = head_.load(std::memory_order_relaxed);
    if (head - tail_cache_ == Capacity) {
      tail_cache_ = tail_.load(std::memory_order_acquire);
      if (head - tail_cache_ == Capacity) return false;
    }
    slots_[head & (Capacity - 1)] = value;
    head_.store(head + 1, std::memory_order_release);
    return true;
  }

  /// Consumer only. False when empty.
  bool pop(T& out) noexcept {
    const std::size_t tail = tail_.load(std::memory_order_relaxed);
    if (tail == head_cache_) {
      head_cache_ = head_.load(std::memory_order_acquire);
      if (tail == head_cache_) return false;
    }
    out = slots_[tail & (Capacity - 1)];
    tail_.store(tail + 1, std::memory_order_release);
    return true;
  }

  /// Approximate number of queued values (exact when called by either side
  /// while the other is idle).
  std::size_t size() const noexcept {
    return head_.load(std::memory_order_acquire) - tail_.load(std::memory_order_acquire);
  }

  static constexpr std::size_t capacity() noexcept { return Capacity; }

 private:
  // Producer-owned and consumer-owned indices on separate cache lines; each
  // side caches the other's index to touch the shared line only when needed.
  alignas(64) std::atomic<std::size_t> head_{0};
  std::size_t tail_cache_ = 0;  // producer's view of tail_
  alignas(64) std::atomic<std::size_t> tail_{0};
  std::size_t head_cache_ = 0;  // consumer's view of head_
  alignas(64) std::array<T, Capacity> slots_{};
};

}  // namespace tsmh::bridge
