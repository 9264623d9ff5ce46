#pragma once
// LatestValue<T>: a single-writer, multi-reader cell holding the newest value
// of a trivially copyable T. Two slots, each a seqlock whose payload is
// stored as relaxed atomic words, so concurrent reads and writes are well
// defined in C++ (and clean under ThreadSanitizer) yet compile to plain moves
// on x86-64. Every hand-over between a real-time thread and another one goes
// through it: the bridge's receive thread to the loop (newest SLAVE_STATE),
// a device driver's I/O thread to the loop (readings) and back (torques).
//
// Why: the writer (a receive or I/O thread) must never wait for the 1 kHz
// loop, and the loop must never wait for the network or the device -- nor for
// the writer. With one slot a reader that meets a store in progress has to
// retry until the store ends; when the writer is preempted mid-store by the
// reader's own SCHED_FIFO thread on the same CPU it never ends, and the loop
// stalls for tens of ms under a flood of SLAVE_STATE. Here the
// writer fills the slot the readers are not directed to and only then
// publishes its version, so a store in progress never blocks a read of the
// previous value; a read retries only when the writer completed a whole store
// and began the next one during its copy, and load() gives up after
// kMaxAttempts (returning 0, the output untouched: the caller keeps the value
// it has). store() and load() are wait-free. A reader never observes a mix of
// two stores (no torn reads). Several readers may load concurrently (the
// bridge's counters are read by any thread), which a triple buffer would not
// allow.
//
// LatestValueReader<T> is one reader's view for readers that need a value on
// every call and whether it is new (the drivers' read() and I/O threads).

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace tsmh::realtime {

template <class T>
class LatestValueReader;

template <class T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>, "LatestValue<T> copies T as raw words");

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
    for (std::size_t i = 0; i < kFullWords; ++i) {
      std::uint64_t w;
      std::memcpy(&w, src + i * 8, 8);
      slot.words[i].store(w, std::memory_order_relaxed);
    }
    if constexpr (kTailBytes != 0) {
      std::uint64_t w = 0;
      std::memcpy(&w, src + kFullWords * 8, kTailBytes);
      slot.words[kFullWords].store(w, std::memory_order_relaxed);
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
  std::uint64_t load(T& out) const noexcept { return load_impl<Output::kUntouchedOnFailure>(out); }

  /// Number of stores so far (0: empty). Cheap: one atomic load.
  std::uint64_t version() const noexcept { return latest_.load(std::memory_order_acquire); }

 private:
  friend class LatestValueReader<T>;

  // kScratch: a failed attempt may leave `out` half written, which saves a
  // copy when `out` is a scratch buffer (LatestValueReader's spare value).
  enum class Output { kUntouchedOnFailure, kScratch };

  template <Output kOut>
  std::uint64_t load_impl(T& out) const noexcept {
    for (int i = 0; i < kMaxAttempts; ++i) {
      const std::uint64_t v = attempt<kOut>(out);
      if (v != 0) return v;
      if (latest_.load(std::memory_order_acquire) == 0) return 0;
    }
    return 0;
  }

  static constexpr std::size_t kWords = (sizeof(T) + 7) / 8;
  // Whole words, then the tail of a size that is not a multiple of 8: the
  // copies have constant sizes, so each word is one move.
  static constexpr std::size_t kFullWords = sizeof(T) / 8;
  static constexpr std::size_t kTailBytes = sizeof(T) % 8;

  // The version copied into `out`, or 0 (out untouched unless kScratch).
  template <Output kOut = Output::kUntouchedOnFailure>
  std::uint64_t attempt(T& out) const noexcept {
    const std::uint64_t v = latest_.load(std::memory_order_acquire);
    if (v == 0) return 0;
    const Slot& slot = slots_[v & 1U];
    const std::uint64_t s0 = slot.seq.load(std::memory_order_acquire);
    if (s0 != 2 * v) return 0;  // the writer has moved on to version v + 2 in this slot
    if constexpr (kOut == Output::kScratch) {
      auto* dst = reinterpret_cast<unsigned char*>(&out);
      for (std::size_t i = 0; i < kFullWords; ++i) {
        const std::uint64_t w = slot.words[i].load(std::memory_order_relaxed);
        std::memcpy(dst + i * 8, &w, 8);
      }
      if constexpr (kTailBytes != 0) {
        const std::uint64_t w = slot.words[kFullWords].load(std::memory_order_relaxed);
        std::memcpy(dst + kFullWords * 8, &w, kTailBytes);
      }
    } else {
      std::array<std::uint64_t, kWords> buf;
      for (std::size_t i = 0; i < kWords; ++i)
        buf[i] = slot.words[i].load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (slot.seq.load(std::memory_order_relaxed) != s0) return 0;
      std::memcpy(static_cast<void*>(&out), buf.data(), sizeof(T));
      return v;
    }
    std::atomic_thread_fence(std::memory_order_acquire);
    return slot.seq.load(std::memory_order_relaxed) == s0 ? v : 0;
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

/// One reader of a LatestValue that needs a value on every call and to know
/// whether it is new: keeps the value it copied last, so fetch() always has
/// one (T{} before the first store; the previous one again when nothing new
/// was stored, or when a load gave up). Two values, the current one and a
/// spare the cell is copied into (and which becomes current when the copy is
/// whole): one copy out of the cell, as a triple buffer would. One thread at
/// a time per reader; a reader may move to another thread only with a
/// happens-before edge in between (e.g. join). Wait-free, as load().
template <class T>
class LatestValueReader {
 public:
  explicit LatestValueReader(const LatestValue<T>& cell) noexcept : cell_(&cell) {}

  /// Copies the newest value into `out`. Returns true when it was stored
  /// after the value the previous fetch() returned (false: `out` is the same
  /// value again).
  bool fetch(T& out) noexcept {
    bool fresh = false;
    if (cell_->version() != seen_) {
      const std::uint64_t v =
          cell_->template load_impl<LatestValue<T>::Output::kScratch>(values_[current_ ^ 1U]);
      fresh = v != 0;
      if (fresh) {
        seen_ = v;
        current_ ^= 1U;
      }
    }
    out = values_[current_];
    return fresh;
  }

 private:
  const LatestValue<T>* cell_;
  std::array<T, 2> values_{};
  unsigned current_ = 0;
  std::uint64_t seen_ = 0;
};

}  // namespace tsmh::realtime
