#pragma once
// LatestValue<T>: a single-writer, multi-reader cell holding the newest value
// of a trivially copyable T. Two slots, each a seqlock whose payload is
// stored as relaxed atomic words, so concurrent reads and writes are well
// defined in C++ (and clean under ThreadSanitizer) yet compile to plain moves
// on x86-64.
//
// Why: the writer (a receive thread) must never wait for the 1 kHz loop, and
// the loop must never wait for the network -- nor for the writer. With one
// slot a reader that meets a store in progress has to retry until the store
// ends; when the writer is preempted mid-store by the reader's own SCHED_FIFO
// thread on the same CPU it never ends, and the loop stalled for 65-144 ms
// under a 29 kHz SLAVE_STATE flood (issue 15). Here the writer fills the
// slot the readers are not directed to and only then publishes its version,
// so a store in progress never blocks a read of the previous value; a read
// retries only when the writer completed a whole store and began the next one
// during its copy, and load() gives up after kMaxAttempts (returning 0, the
// output untouched: the caller keeps the value it has). store() and load()
// are wait-free. A reader never observes a mix of two stores (no torn reads).

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace tsmh::bridge {

template <class T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>, "LatestValue<T> copies T as raw words");
  static_assert(std::is_default_constructible_v<T>);

 public:
  LatestValue() = default;
  LatestValue(const LatestValue&) = delete;
  LatestValue& operator=(const LatestValue&) = delete;

  /// At most this many copies per load(): a retry needs the writer to finish
  /// a whole store during the reader's copy, so more than two attempts
  /// practically never happen outside a preempted reader.
  static constexpr int kMaxAttempts = 8;

  /// Publishes `value`. Only one thread may call store() (the single writer).
  void store(const T& value) noexcept {
    const std::uint64_t v = latest_.load(std::memory_order_relaxed) + 1;
    Slot& slot = slots_[v & 1U];
    slot.seq.store(2 * v - 1, std::memory_order_relaxed);  // odd: a store is in progress
    std::atomic_thread_fence(std::memory_order_release);
    const auto* src = reinterpret_cast<const unsigned char*>(&value);
    for (std::size_t i = 0; i < kWords; ++i) {
      std::uint64_t w = 0;
      std::memcpy(&w, src + i * 8, bytes_in_word(i));
      slot.words[i].store(w, std::memory_order_relaxed);
    }
    slot.seq.store(2 * v, std::memory_order_release);  // even: stable again
    latest_.store(v, std::memory_order_release);       // readers now go to this slot
  }

  /// One attempt to copy the newest value into `out`. Returns false, leaving
  /// `out` untouched, when nothing was stored yet or the writer overwrote the
  /// slot during the copy.
  bool try_load(T& out) const noexcept { return attempt(out) != 0; }

  /// Copies the newest value into `out` and returns its version (1 for the
  /// first store, +1 per store). Returns 0 and leaves `out` untouched when
  /// nothing was stored yet, or (practically never) when kMaxAttempts copies
  /// all overlapped a store: either way the caller keeps what it has.
  /// Compare versions to tell whether a value is new.
  std::uint64_t load(T& out) const noexcept {
    for (int i = 0; i < kMaxAttempts; ++i) {
      const std::uint64_t v = attempt(out);
      if (v != 0) return v;
      if (latest_.load(std::memory_order_acquire) == 0) return 0;
    }
    return 0;
  }

  /// Number of stores so far (0: empty). Cheap: one atomic load.
  std::uint64_t version() const noexcept { return latest_.load(std::memory_order_acquire); }

 private:
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;
  static constexpr std::size_t bytes_in_word(std::size_t i) noexcept {
    return (i + 1 < kWords || sizeof(T) % 8 == 0) ? 8 : sizeof(T) % 8;
  }

  // The version copied into `out`, or 0 (out untouched).
  std::uint64_t attempt(T& out) const noexcept {
    const std::uint64_t v = latest_.load(std::memory_order_acquire);
    if (v == 0) return 0;
    const Slot& slot = slots_[v & 1U];
    const std::uint64_t s0 = slot.seq.load(std::memory_order_acquire);
    if (s0 != 2 * v) return 0;  // the writer has moved on to version v + 2 in this slot
    std::array<std::uint64_t, kWords> buf;
    for (std::size_t i = 0; i < kWords; ++i)
      buf[i] = slot.words[i].load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (slot.seq.load(std::memory_order_relaxed) != s0) return 0;
    std::memcpy(static_cast<void*>(&out), buf.data(), sizeof(T));
    return v;
  }

  // Separate cache lines: readers polling a seq do not contend with the
  // payload lines the writer is filling.
  struct Slot {
    alignas(64) std::atomic<std::uint64_t> seq{0};
    alignas(64) std::array<std::atomic<std::uint64_t>, kWords> words{};
  };
  alignas(64) std::atomic<std::uint64_t> latest_{0};
  std::array<Slot, 2> slots_{};
};

}  // namespace tsmh::bridge
