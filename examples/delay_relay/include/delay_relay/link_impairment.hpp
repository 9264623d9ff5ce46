#pragma once
// What a long network does to one direction of a teleoperation link (issue
// 21): a constant delay, plus jitter, plus a fraction of the messages lost.
// Pure and deterministic for a given seed, so tests and the benchmark
// scenario replay exactly; the LCM relay (lcm-delay-relay) and the offline
// benchmark (bench_teleop_delay) share it.
//
// Order is kept: a message never overtakes an earlier one (release times
// never decrease). A reordering network would only make the receiver drop
// the late message (the bridge drops reordered samples), i.e. more loss,
// which drop_fraction models directly.

#include <cstdint>
#include <deque>
#include <utility>

namespace tsmh::delay_relay {

struct ImpairmentParams {
  double delay_s = 0.0;        ///< constant one-way delay, >= 0
  double jitter_s = 0.0;       ///< + uniform in [-jitter, +jitter]; <= delay_s (never before now)
  double drop_fraction = 0.0;  ///< 0..1: probability that a message is lost
};

/// Throws std::invalid_argument naming `where` and the field.
void validate(const ImpairmentParams& p, const char* where);

/// Small, fast, portable generator (splitmix64): the same seed gives the same
/// sequence on every platform, unlike the distributions of <random>.
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) noexcept : s_(seed) {}
  std::uint64_t next() noexcept {
    std::uint64_t z = (s_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  double uniform() noexcept { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

 private:
  std::uint64_t s_;
};

class LinkImpairment {
 public:
  static constexpr std::int64_t kDropped = -1;

  LinkImpairment(const ImpairmentParams& p, std::uint64_t seed);

  /// A message arriving at arrival_ns: kDropped, or the time to release it
  /// (>= arrival_ns, and >= the previous release: order kept).
  std::int64_t schedule(std::int64_t arrival_ns) noexcept;

  std::uint64_t passed() const noexcept { return passed_; }
  std::uint64_t dropped() const noexcept { return dropped_; }
  const ImpairmentParams& params() const noexcept { return p_; }

 private:
  ImpairmentParams p_;
  SplitMix64 rng_;
  std::int64_t last_release_ns_ = INT64_MIN;
  std::uint64_t passed_ = 0;
  std::uint64_t dropped_ = 0;
};

/// A LinkImpairment plus the messages in flight.
template <class Payload>
class DelayLine {
 public:
  DelayLine(const ImpairmentParams& p, std::uint64_t seed) : link_(p, seed) {}

  /// Returns false when the message is dropped.
  bool push(std::int64_t arrival_ns, Payload payload) {
    const std::int64_t at = link_.schedule(arrival_ns);
    if (at == LinkImpairment::kDropped) return false;
    queue_.emplace_back(at, std::move(payload));
    return true;
  }
  /// The oldest message due at now_ns, if any, into `out`.
  bool pop_due(std::int64_t now_ns, Payload& out) {
    if (queue_.empty() || queue_.front().first > now_ns) return false;
    out = std::move(queue_.front().second);
    queue_.pop_front();
    return true;
  }
  /// Release time of the next message; INT64_MAX when none is in flight.
  std::int64_t next_release_ns() const noexcept {
    return queue_.empty() ? INT64_MAX : queue_.front().first;
  }
  std::size_t in_flight() const noexcept { return queue_.size(); }
  const LinkImpairment& link() const noexcept { return link_; }

 private:
  LinkImpairment link_;
  std::deque<std::pair<std::int64_t, Payload>> queue_;
};

}  // namespace tsmh::delay_relay
