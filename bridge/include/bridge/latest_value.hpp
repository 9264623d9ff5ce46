#pragma once
// LatestValue<T>: a single-writer, multi-reader cell holding the newest value
// of a trivially copyable T. It is a seqlock whose payload is stored as relaxed
// atomic words, so concurrent reads and writes are well defined in C++ (and
// clean under ThreadSanitizer) yet compile to plain moves on x86-64.
//
// Why a seqlock: the writer (a receive thread) must never wait for the 1 kHz
// loop, and the loop must never wait for the network. store() is wait-free.
// load() copies the words and retries only when a store overlapped the copy;
// a store takes well under a microsecond and happens at most a few thousand
// times per second, so a second attempt is rare and a third practically never
// happens. A reader never observes a mix of two stores (no torn reads).

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

  /// Publishes `value`. Only one thread may call store() (the single writer).
  void store(const T& value) noexcept {
    const std::uint64_t s = seq_.load(std::memory_order_relaxed);
    seq_.store(s + 1, std::memory_order_relaxed);  // odd: a store is in progress
    std::atomic_thread_fence(std::memory_order_release);
    const auto* src = reinterpret_cast<const unsigned char*>(&value);
    for (std::size_t i = 0; i < kWords; ++i) {
      std::uint64_t w = 0;
      std::memcpy(&w, src + i * 8, bytes_in_word(i));
      words_[i].store(w, std::memory_order_relaxed);
    }
    seq_.store(s + 2, std::memory_order_release);  // even: stable again
  }

  /// One attempt to copy the newest value into `out`. Returns false, leaving
  /// `out` untouched, when nothing was stored yet or a store overlapped.
  bool try_load(T& out) const noexcept {
    const std::uint64_t s0 = seq_.load(std::memory_order_acquire);
    if (s0 == 0 || (s0 & 1U) != 0) return false;
    std::array<std::uint64_t, kWords> buf;
    for (std::size_t i = 0; i < kWords; ++i)
      buf[i] = words_[i].load(std::memory_order_relaxed);
    std::atomic_thread_fence(std::memory_order_acquire);
    if (seq_.load(std::memory_order_relaxed) != s0) return false;
    std::memcpy(static_cast<void*>(&out), buf.data(), sizeof(T));
    return true;
  }

  /// Copies the newest value into `out` and returns its version (1 for the
  /// first store, +1 per store); returns 0 and leaves `out` untouched when
  /// nothing was stored yet. Compare versions to tell whether a value is new.
  std::uint64_t load(T& out) const noexcept {
    for (;;) {
      const std::uint64_t s0 = seq_.load(std::memory_order_acquire);
      if (s0 == 0) return 0;
      if ((s0 & 1U) != 0) continue;  // a store is in progress: it ends within nanoseconds
      std::array<std::uint64_t, kWords> buf;
      for (std::size_t i = 0; i < kWords; ++i)
        buf[i] = words_[i].load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) != s0) continue;
      std::memcpy(static_cast<void*>(&out), buf.data(), sizeof(T));
      return s0 / 2;
    }
  }

  /// Number of stores so far (0: empty). Cheap: one atomic load.
  std::uint64_t version() const noexcept { return seq_.load(std::memory_order_acquire) / 2; }

 private:
  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;
  static constexpr std::size_t bytes_in_word(std::size_t i) noexcept {
    return (i + 1 < kWords || sizeof(T) % 8 == 0) ? 8 : sizeof(T) % 8;
  }

  // Separate cache lines: readers polling seq_ do not contend with the
  // payload lines the writer is filling.
  alignas(64) std::atomic<std::uint64_t> seq_{0};
  alignas(64) std::array<std::atomic<std::uint64_t>, kWords> words_{};
};

}  // namespace tsmh::bridge
