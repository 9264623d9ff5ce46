#include "bridge/link_session.hpp"

#include "realtime/enum_names.hpp"

namespace tsmh::bridge {

const char* to_string(SessionState s) noexcept {
  return realtime::enum_name<SessionState::kFault>(s, {"open", "bound", "closed", "FAULT"}).data();
}

LinkSession::LinkSession(MessageSigner& signer, SessionOptions options)
    : signer_(signer), my_id_(signer.sender_id()), options_(options) {
  signer_.set_peer_id(0);
}

void LinkSession::name(std::uint64_t peer) noexcept {
  // After close() every message says goodbye, whatever happens here.
  if (!closing_.load(std::memory_order_acquire)) signer_.set_peer_id(peer);
}

void LinkSession::close() noexcept {
  closing_.store(true, std::memory_order_release);
  // A session that ended in FAULT does not say a clean goodbye: its peer
  // must not take the next master as if nothing had happened.
  if (state() != SessionState::kFault) signer_.set_peer_id(kSessionClosedPeer);
}

void LinkSession::bind(std::uint64_t peer, std::int64_t now_ns) noexcept {
  peer_.store(peer, std::memory_order_release);
  peer_heard_ns_ = now_ns;
  candidate_ = 0;
  name(peer);
  binds_.fetch_add(1, std::memory_order_relaxed);
  state_.store(SessionState::kBound, std::memory_order_release);
}

void LinkSession::reopen() noexcept {
  peer_.store(0, std::memory_order_release);
  candidate_ = 0;
  name(0);
  state_.store(options_.rearm ? SessionState::kOpen : SessionState::kClosed,
               std::memory_order_release);
}

SessionVerdict LinkSession::conflict(const AuthTrailer& t) noexcept {
  other_session_.fetch_add(1, std::memory_order_relaxed);
  if (state() != SessionState::kFault) {
    fault_sender_.store(t.sender_id, std::memory_order_release);
    fault_names_.store(t.peer_id, std::memory_order_release);
    peer_.store(0, std::memory_order_release);
    state_.store(SessionState::kFault, std::memory_order_release);
    // Tell it: the former peer's session ends in FAULT too, and so does any
    // other that hears us (set even after close(): a fault is no goodbye).
    signer_.set_peer_id(kSessionFaultPeer);
  }
  return SessionVerdict::kOtherSession;
}

void LinkSession::tick(std::int64_t now_ns) noexcept {
  const SessionState s = state();
  if (s == SessionState::kBound && options_.rearm && now_ns - peer_heard_ns_ > options_.timeout_ns)
    reopen();  // the peer fell silent: a slave holds and serves the next master
  if (state() == SessionState::kOpen && candidate_ != 0 &&
      now_ns - candidate_ns_ > options_.timeout_ns) {
    candidate_ = 0;
    name(0);
  }
}

SessionVerdict LinkSession::observe(const AuthTrailer& t, std::int64_t now_ns) noexcept {
  const std::uint64_t from = t.sender_id;
  const std::uint64_t names = t.peer_id;
  SessionState s = state();
  if (s == SessionState::kFault) {
    if (from != fault_sender_.load(std::memory_order_relaxed))
      other_session_.fetch_add(1, std::memory_order_relaxed);
    return SessionVerdict::kEnded;
  }
  // A peer that said goodbye is gone for good: its late (reordered) messages
  // must not bind it again, nor count against the next peer.
  if (from == gone_peer_ && gone_peer_ != 0) return SessionVerdict::kEnded;
  if (s == SessionState::kBound && options_.rearm &&
      now_ns - peer_heard_ns_ > options_.timeout_ns) {
    reopen();  // the peer fell silent: a slave holds and serves the next master
    s = state();
  }
  // A session in FAULT (the peer's, or another's on this channel): FAULT here too.
  if (names == kSessionFaultPeer) return conflict(t);
  // A goodbye from anyone but the bound peer binds, moves and ends nothing.
  if (names == kSessionClosedPeer && !(s == SessionState::kBound && from == peer()))
    return SessionVerdict::kEnded;

  switch (s) {
    case SessionState::kBound: {
      if (from != peer()) return conflict(t);
      if (names == my_id_) {
        peer_heard_ns_ = now_ns;
        return SessionVerdict::kAccept;
      }
      if (names == 0) return SessionVerdict::kHandshake;  // sent before it heard our answer
      if (names == kSessionClosedPeer) {
        gone_peer_ = from;
        reopen();
        return SessionVerdict::kAccept;  // its last word (a hold) still counts
      }
      return conflict(t);  // our peer is bound to someone else
    }
    case SessionState::kOpen: {
      if (names == my_id_) {
        // Only a process that heard this end's messages (its id is random per
        // process: a nonce) can name it; a recording of an older session names
        // an older id and ends below.
        bind(from, now_ns);
        return SessionVerdict::kAccept;
      }
      if (names != 0) return conflict(t);
      if (candidate_ != 0 && candidate_ != from && now_ns - candidate_ns_ <= options_.timeout_ns)
        return conflict(t);  // two live hellos: two peers want this end
      candidate_ = from;
      candidate_ns_ = now_ns;
      name(from);
      return SessionVerdict::kHandshake;
    }
    case SessionState::kClosed:
      return conflict(t);  // the session is over: anyone else is another session
    case SessionState::kFault:
      break;
  }
  return SessionVerdict::kEnded;
}

}  // namespace tsmh::bridge
