#pragma once
// Inbox<Sample>: the newest valid sample of one incoming channel, for the loop.
//
// The receive thread (Receiver) feeds every raw message of the channel into
// ingest(): decode without trusting the bytes, check joint count and content,
// classify the ordering, count, and store accepted samples in a LatestValue.
// The loop calls latest(): a lock-free copy of the newest accepted sample
// (~tens of ns, never blocks, never torn) whose receive_ns gives its age.

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "bridge/channel_stats.hpp"
#include "bridge/codec.hpp"
#include "bridge/link_auth.hpp"
#include "bridge/link_session.hpp"
#include "bridge/rejection.hpp"
#include "bridge/sequence_tracker.hpp"
#include "realtime/histogram.hpp"
#include "realtime/latest_value.hpp"

namespace tsmh::bridge {

template <class Sample>
struct InboxOptions {
  /// Required num_joints; 0 accepts any count in 1..kMaxJoints.
  int expected_joints = 0;
  /// Plausibility ranges; a value outside rejects the message.
  typename SampleTraits<Sample>::Limits limits{};
  /// Sender and receiver share CLOCK_MONOTONIC (same host): record one-way
  /// latency = receive time - utime. Set false across hosts.
  bool clocks_shared = true;
  /// Full channel name; empty: the Receiver's prefix + the base name.
  std::string channel{};
  /// See SequenceTracker.
  int resync_after = 50;
  /// A session channel (keyed Receiver only): every authentic message is put
  /// to this session (bridge/link_session.hpp) before it is decoded; only its
  /// bound peer's are used. Null: any sender with the key (CALIBRATION_REQUEST).
  LinkSession* session = nullptr;
};

/// The type-independent part: counters and the receive-thread entry point.
class InboxBase {
 public:
  explicit InboxBase(std::string channel) : channel_(std::move(channel)) {}
  virtual ~InboxBase() = default;
  InboxBase(const InboxBase&) = delete;
  InboxBase& operator=(const InboxBase&) = delete;

  /// Receive thread only (single writer): handles one raw message that
  /// arrived at `receive_ns` (CLOCK_MONOTONIC). Never throws.
  virtual void ingest(const void* data, std::size_t size, std::int64_t receive_ns) noexcept = 0;

  /// Receive thread only: a message that failed authentication (verdict not
  /// Ok) is counted as received and rejected by its reason; it never reaches
  /// the decoder.
  void reject_unauthentic(const AuthResult& auth, std::int64_t receive_ns) noexcept;
  /// Receive thread only: an authentic message the session did not accept
  /// (verdict not Accept): a handshake message is counted as such, another
  /// session's or one after the end as rejected.
  void refuse_by_session(SessionVerdict verdict, const AuthTrailer& trailer,
                         std::int64_t receive_ns) noexcept;
  /// The session this channel belongs to; null for none.
  LinkSession* session() const noexcept { return session_; }

  const std::string& channel() const noexcept { return channel_; }
  /// Any thread.
  ChannelStats stats() const noexcept;
  /// The most recent rejection, if any (any thread).
  std::optional<Rejection> last_rejection() const noexcept;

  /// Receiver only, before its receive thread starts: messages that queued up
  /// between subscribe() and start() are old by the time anyone reads them;
  /// they are counted (ChannelStats::discarded_before_start) and dropped
  /// instead of being handed to the loop as if they had just arrived.
  void set_discarding(bool on) noexcept { discarding_ = on; }
  bool discarding() const noexcept { return discarding_; }
  void count_discarded() noexcept { discarded_.fetch_add(1, std::memory_order_relaxed); }

 protected:
  void count_received() noexcept { received_.fetch_add(1, std::memory_order_relaxed); }
  void count_rejected(const Rejection& r) noexcept;
  /// Counts an ordering verdict; returns whether the sample is to be accepted.
  bool count_order(const OrderVerdict& v, std::int64_t seq, std::int64_t utime,
                   std::int64_t receive_ns) noexcept;
  void count_accepted(std::int64_t utime, std::int64_t receive_ns, bool clocks_shared) noexcept;
  void count_resync() noexcept { count(Order::kResync); }
  LinkSession* session_ = nullptr;

 private:
  std::string channel_;
  std::atomic<std::uint64_t> received_{0};
  std::atomic<std::uint64_t> accepted_{0};
  std::array<std::atomic<std::uint64_t>, kRejectReasons> rejected_by_{};
  std::atomic<std::uint64_t> handshake_{0};
  void count(Order order) noexcept {
    by_order_[static_cast<std::size_t>(order)].fetch_add(1, std::memory_order_relaxed);
  }
  std::uint64_t counted(Order order) const noexcept {
    return by_order_[static_cast<std::size_t>(order)].load(std::memory_order_relaxed);
  }
  /// Messages per ordering verdict (duplicates, reordered, gaps as events,
  /// restarts, resyncs), indexed by Order.
  std::array<std::atomic<std::uint64_t>, kOrders> by_order_{};
  std::atomic<std::uint64_t> seq_missing_{0};
  std::atomic<std::uint64_t> discarded_{0};
  bool discarding_ = false;
  std::atomic<std::int64_t> last_receive_ns_{0};
  realtime::LogHistogram latency_;
  realtime::LatestValue<Rejection> last_rejection_;
};

template <class Sample>
class Inbox final : public InboxBase {
 public:
  Inbox(std::string channel, InboxOptions<Sample> options);

  /// Loop side. Copies the newest accepted sample into `out` and returns its
  /// version (+1 per accepted sample); 0 when none has arrived yet (`out`
  /// untouched). Lock-free, no allocation, no system call.
  std::uint64_t latest(Sample& out) const noexcept { return cell_.load(out); }
  /// Version of the newest accepted sample without copying it.
  std::uint64_t version() const noexcept { return cell_.version(); }

  void ingest(const void* data, std::size_t size, std::int64_t receive_ns) noexcept override;

  const InboxOptions<Sample>& options() const noexcept { return options_; }

 private:
  InboxOptions<Sample> options_;
  Decoder<Sample> decoder_;
  SequenceTracker tracker_;
  Sample scratch_{};
  Sample last_accepted_{};  // the reference of the plausibility check (check_step)
  bool has_accepted_ = false;
  Sample candidate_{};     // the newest sample rejected as Implausible
  int candidate_run_ = 0;  // consecutive Implausible rejections that follow each other plausibly
  realtime::LatestValue<Sample> cell_;
};

// The members not defined above are compiled in inbox.cpp, once for each sample
// type of SampleTraits (codec.hpp).

}  // namespace tsmh::bridge
