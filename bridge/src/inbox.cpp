#include "bridge/inbox.hpp"

#include <algorithm>
#include <cstdio>

#include "bridge/validation.hpp"

namespace tsmh::bridge {

ChannelStats InboxBase::stats() const noexcept {
  ChannelStats s;
  s.received = received_.load(std::memory_order_relaxed);
  s.accepted = accepted_.load(std::memory_order_relaxed);
  for (std::size_t i = 0; i < s.rejected_by.size(); ++i)
    s.rejected_by[i] = rejected_by_[i].load(std::memory_order_relaxed);
  s.handshake = handshake_.load(std::memory_order_relaxed);
  s.duplicates = counted(Order::kDuplicate);
  s.reordered = counted(Order::kLate);
  s.seq_gaps = counted(Order::kGap);
  s.seq_missing = seq_missing_.load(std::memory_order_relaxed);
  s.restarts = counted(Order::kRestart);
  s.resyncs = counted(Order::kResync);
  s.discarded_before_start = discarded_.load(std::memory_order_relaxed);
  s.latency = latency_.summary();
  s.last_receive_ns = last_receive_ns_.load(std::memory_order_relaxed);
  return s;
}

std::optional<Rejection> InboxBase::last_rejection() const noexcept {
  Rejection r;
  if (last_rejection_.load(r) == 0) return std::nullopt;
  return r;
}

void InboxBase::count_rejected(const Rejection& r) noexcept {
  rejected_by_[static_cast<std::size_t>(r.reason)].fetch_add(1, std::memory_order_relaxed);
  last_rejection_.store(r);
}

void InboxBase::reject_unauthentic(const AuthResult& auth, std::int64_t receive_ns) noexcept {
  count_received();
  RejectReason reason = RejectReason::kUnauthenticated;
  switch (auth.verdict) {
    case AuthVerdict::kOk:
    case AuthVerdict::kMissing:
    case AuthVerdict::kVersion1:
      break;
    case AuthVerdict::kBadMac:
      reason = RejectReason::kBadMac;
      break;
    case AuthVerdict::kStale:
      reason = RejectReason::kStale;
      break;
    case AuthVerdict::kReplayed:
      reason = RejectReason::kReplayed;
      break;
  }
  char what[64];
  if (auth.verdict == AuthVerdict::kMissing)
    std::snprintf(what, sizeof what, "no trailer");
  else if (auth.verdict == AuthVerdict::kVersion1)
    std::snprintf(what, sizeof what, "trailer version 1 (a sender from before sessions)");
  else
    std::snprintf(what, sizeof what, "sender %016llx seq %llu",
                  static_cast<unsigned long long>(auth.trailer.sender_id),
                  static_cast<unsigned long long>(auth.trailer.seq));
  Rejection r = make_rejection(reason, what, static_cast<double>(auth.age_us));
  r.receive_ns = receive_ns;
  count_rejected(r);
}

void InboxBase::refuse_by_session(SessionVerdict verdict, const AuthTrailer& trailer,
                                  std::int64_t receive_ns) noexcept {
  count_received();
  if (verdict == SessionVerdict::kHandshake) {
    handshake_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  char what[64];
  std::snprintf(what, sizeof what, "sender %016llx naming %016llx",
                static_cast<unsigned long long>(trailer.sender_id),
                static_cast<unsigned long long>(trailer.peer_id));
  Rejection r =
      make_rejection(verdict == SessionVerdict::kOtherSession ? RejectReason::kOtherSession
                                                              : RejectReason::kSessionEnded,
                     what);
  r.receive_ns = receive_ns;
  count_rejected(r);
}

bool InboxBase::count_order(const OrderVerdict& v, std::int64_t seq, std::int64_t utime,
                            std::int64_t receive_ns) noexcept {
  // One event per verdict: a gap counts once whatever its width, so a single
  // bogus seq of 2e12 reads as one gap, not two trillion (and never overflows).
  count(v.order);
  if (v.order == Order::kGap) {
    // single writer (the receive thread): load + store is enough
    const std::uint64_t had = seq_missing_.load(std::memory_order_relaxed);
    const auto add = static_cast<std::uint64_t>(v.missing);
    seq_missing_.store(had > UINT64_MAX - add ? UINT64_MAX : had + add, std::memory_order_relaxed);
  } else if (v.order == Order::kTimeBackwards) {
    auto r =
        make_rejection(RejectReason::kTimeBackwards, "seq advanced", static_cast<double>(utime));
    r.seq = seq;
    r.receive_ns = receive_ns;
    count_rejected(r);
  }
  return v.accepted();
}

void InboxBase::count_accepted(std::int64_t utime, std::int64_t receive_ns,
                               bool clocks_shared) noexcept {
  if (clocks_shared) latency_.record(receive_ns - utime * 1000);
  last_receive_ns_.store(receive_ns, std::memory_order_relaxed);
  accepted_.fetch_add(1, std::memory_order_relaxed);
}

namespace {

// check_step() over the interval between two samples: the smaller of the
// sender's (utime) and the receiver's (receive_ns) interval, so a forged utime
// cannot widen the bound (doubles: a hostile utime must not overflow).
template <class Sample, class Limits>
std::optional<Rejection> step_check(const Sample& prev, const Sample& next,
                                    const Limits& limits) noexcept {
  const double utime_s = (static_cast<double>(next.utime) - static_cast<double>(prev.utime)) * 1e-6;
  const double receive_s =
      (static_cast<double>(next.receive_ns) - static_cast<double>(prev.receive_ns)) * 1e-9;
  return bridge::check_step(prev, next, std::min(std::max(utime_s, 0.0), receive_s), limits);
}

}  // namespace

template <class Sample>
Inbox<Sample>::Inbox(std::string channel, InboxOptions<Sample> options)
    : InboxBase(std::move(channel)), options_(std::move(options)), tracker_(options_.resync_after) {
  session_ = options_.session;
}

template <class Sample>
void Inbox<Sample>::ingest(const void* data, std::size_t size, std::int64_t receive_ns) noexcept {
  count_received();
  auto reject = [&](Rejection r) {
    r.receive_ns = receive_ns;
    count_rejected(r);
  };
  if (auto r = decoder_.decode(data, size, scratch_)) return reject(*r);
  if (auto r = check_joint_count(scratch_.num_joints, options_.expected_joints)) {
    r->seq = scratch_.seq;
    return reject(*r);
  }
  if (auto r = validate(scratch_, options_.limits)) {
    r->seq = scratch_.seq;
    return reject(*r);
  }
  bool rebased = false;
  if (has_accepted_) {
    scratch_.receive_ns = receive_ns;
    if (auto r = step_check(last_accepted_, scratch_, options_.limits)) {
      // A re-homed slave sends a new trajectory that is consistent in itself;
      // random garbage never is. Re-base only on resync_after rejected
      // samples in a row that each follow the previous one plausibly.
      const bool continues =
          candidate_run_ > 0 && !step_check(candidate_, scratch_, options_.limits);
      candidate_run_ = continues ? candidate_run_ + 1 : 1;
      candidate_ = scratch_;
      if (candidate_run_ < options_.resync_after) {
        r->seq = scratch_.seq;
        return reject(*r);
      }
      rebased = true;
    }
  }
  const OrderVerdict v = tracker_.observe(scratch_.seq, scratch_.utime);
  if (!count_order(v, scratch_.seq, scratch_.utime, receive_ns)) return;
  candidate_run_ = 0;
  if (rebased) count_resync();
  scratch_.receive_ns = receive_ns;
  last_accepted_ = scratch_;
  has_accepted_ = true;
  cell_.store(scratch_);
  count_accepted(scratch_.utime, receive_ns, options_.clocks_shared);
}

template class Inbox<SlaveStateSample>;
template class Inbox<SlaveTruthSample>;
template class Inbox<MasterCommandSample>;
template class Inbox<HapticStatusSample>;
template class Inbox<CalibrationRequestSample>;

}  // namespace tsmh::bridge
