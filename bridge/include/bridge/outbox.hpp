#pragma once
// Outbox<Sample>: the loop's non-blocking way to publish one channel.
//
// publish() copies the sample into a wait-free SPSC ring and wakes the
// Sender's publish thread, which encodes and sends it. Publishing directly
// from the loop costs a sendmsg() system call per message whose duration is
// not bounded (docs/bridge.md has the measurements), so the loop only pays
// for a ~100-byte..1-KiB copy and a futex wake. When the ring is full the
// sample is dropped and counted: the loop never waits.

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "bridge/codec.hpp"
#include "bridge/link_auth.hpp"
#include "bridge/spsc_queue.hpp"

namespace lcm {
class LCM;
}

namespace tsmh::bridge {

struct OutboxStats {
  std::uint64_t queued = 0;          ///< accepted by publish()
  std::uint64_t dropped_full = 0;    ///< refused by publish(): ring full
  std::uint64_t published = 0;       ///< handed to LCM successfully
  std::uint64_t publish_errors = 0;  ///< LCM publish failures
};

/// Wakes the publish thread. Lives in the Sender; outboxes share it. In
/// polling mode (SenderOptions::poll_period > 0) notify() does nothing and the
/// publish thread wakes on its own period, so publish() makes no system call.
class PublishSignal {
 public:
  explicit PublishSignal(bool wake_on_publish = true) noexcept
      : wake_on_publish_(wake_on_publish) {}
  void notify() noexcept {
    if (!wake_on_publish_) return;
    work_.fetch_add(1, std::memory_order_release);
    work_.notify_one();
  }
  std::uint32_t current() const noexcept { return work_.load(std::memory_order_acquire); }
  /// Blocks while the counter still equals `seen` (publish thread only).
  void wait_change(std::uint32_t seen) const noexcept {
    work_.wait(seen, std::memory_order_acquire);
  }
  /// Wakes the publish thread regardless of the mode (stop()).
  void force() noexcept {
    work_.fetch_add(1, std::memory_order_release);
    work_.notify_one();
  }

 private:
  bool wake_on_publish_;
  std::atomic<std::uint32_t> work_{0};
};

class OutboxBase {
 public:
  OutboxBase(std::string channel, PublishSignal& signal)
      : channel_(std::move(channel)), signal_(signal) {}
  virtual ~OutboxBase() = default;
  OutboxBase(const OutboxBase&) = delete;
  OutboxBase& operator=(const OutboxBase&) = delete;

  /// Publish thread only: sends everything queued, each followed by its
  /// authentication trailer when `signer` is set; returns how many.
  virtual std::size_t flush(lcm::LCM& lcm, MessageSigner* signer) noexcept = 0;

  const std::string& channel() const noexcept { return channel_; }
  OutboxStats stats() const noexcept;

 protected:
  std::string channel_;
  PublishSignal& signal_;
  std::atomic<std::uint64_t> queued_{0};
  std::atomic<std::uint64_t> dropped_full_{0};
  std::atomic<std::uint64_t> published_{0};
  std::atomic<std::uint64_t> publish_errors_{0};
};

template <class Sample>
class Outbox final : public OutboxBase {
 public:
  /// 256 samples: at 1 kHz the publish thread may stall for 256 ms before
  /// anything is dropped (stalls of 64+ ms were seen on a loaded 2-core VM).
  static constexpr std::size_t kCapacity = 256;

  using OutboxBase::OutboxBase;

  /// Loop side, one producer thread per outbox. Never blocks or allocates;
  /// false (and counted) when the ring is full. The caller sets utime
  /// (realtime::monotonic_utime()) and seq.
  bool publish(const Sample& s) noexcept {
    if (!queue_.push(s)) {
      dropped_full_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    queued_.fetch_add(1, std::memory_order_relaxed);
    signal_.notify();
    return true;
  }

  std::size_t flush(lcm::LCM& lcm, MessageSigner* signer) noexcept override;

 private:
  SpscQueue<Sample, kCapacity> queue_;
  Sample pending_{};
  typename SampleTraits<Sample>::Message msg_{};
  std::vector<std::uint8_t> bytes_;
};

// The members not defined above are compiled in outbox.cpp, once for each sample
// type of SampleTraits (codec.hpp).

}  // namespace tsmh::bridge
