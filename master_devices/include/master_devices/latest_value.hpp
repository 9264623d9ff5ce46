#pragma once
// A lock-free latest-value cell (triple buffer) for handing the newest sample
// from one thread to another. The writer never waits for the reader and the
// reader always gets the newest complete value: exactly what a real-time loop
// needs from an I/O thread (and the way back for torque commands). No
// allocation, no locks, wait-free on both sides.
//
// One writer thread and one reader thread at a time. A side may move to
// another thread only with a happens-before edge in between (e.g. join).

#include <array>
#include <atomic>
#include <cstdint>
#include <type_traits>

namespace tsmh::master_devices {

template <class T>
class LatestValue {
  static_assert(std::is_trivially_copyable_v<T>, "LatestValue copies values with plain assignment");

 public:
  LatestValue() = default;
  explicit LatestValue(const T& initial) { slots_.fill(initial); }
  LatestValue(const LatestValue&) = delete;
  LatestValue& operator=(const LatestValue&) = delete;

  /// Writer side: makes `value` the newest.
  void publish(const T& value) noexcept {
    slots_[write_] = value;
    const std::uint8_t previous = middle_.exchange(write_ | kFresh, std::memory_order_acq_rel);
    write_ = previous & kIndexMask;
  }

  /// Reader side: copies the newest value into `out`. Returns true when it was
  /// published after the previous fetch (false: `out` is the same value again).
  bool fetch(T& out) noexcept {
    bool fresh = false;
    if (middle_.load(std::memory_order_relaxed) & kFresh) {
      const std::uint8_t previous = middle_.exchange(read_, std::memory_order_acq_rel);
      read_ = previous & kIndexMask;
      fresh = true;
    }
    out = slots_[read_];
    return fresh;
  }

 private:
  static constexpr std::uint8_t kIndexMask = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;

  // Separate cache lines would avoid false sharing, but T is copied whole
  // every tick anyway; the three slots together are what the cell costs.
  std::array<T, 3> slots_{};
  std::atomic<std::uint8_t> middle_{1};
  std::uint8_t write_ = 0;  // owned by the writer
  std::uint8_t read_ = 2;   // owned by the reader
};

}  // namespace tsmh::master_devices
