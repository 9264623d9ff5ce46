#pragma once
// One master, one slave: the session on a keyed link (docs/bridge.md,
// "Sessions").
//
// Every keyed message names, in its trailer's peer id, the session its
// sender is bound to (bridge/link_auth.hpp). A LinkSession is one end of a
// link: its own id is its MessageSigner's sender id (random per process, so
// it doubles as this receiver's nonce), and it writes the peer it binds to
// (or answers in the handshake) into that signer, so every message this end
// publishes names it. On the session channels (SLAVE_STATE into the server,
// MASTER_COMMAND into a slave, MASTER_STATE into the server's `lcm` master
// driver, MASTER_FORCE into a master adapter) the receive thread asks
// observe() about every authenticated message before the payload is used:
//
//   open (not bound), sender X names 0      hello: X becomes the candidate,
//                                           our messages name X; content unused
//   open, X names my id                     X answered: bound to X; accepted
//   bound to X, X names my id               accepted
//   bound to X, X names 0                   a hello of X still in flight: unused
//   bound to X, X names "closed"            X ended the session deliberately: the
//                                           message (a hold) is accepted, then
//                                           closed (re-armed if rearm_after_close)
//   anything else from a sender with the key: another session, a second
//   process joining, a restarted peer, a replay of an old session (it names
//   an id that is not mine), a session in FAULT (it names "fault"): refused
//   as other_session and the session ends in FAULT for good (also when
//   still open: a message naming another id never binds anything, and a
//   second live hello is a conflict too). A session in FAULT names "fault",
//   so its peer ends in FAULT too.
//
// Messages that fail authentication never get here: nobody without the key
// can bind or end a session. Pure logic: no clock of its own (times are the
// caller's CLOCK_MONOTONIC), no allocation; observe() from one thread (the
// receive thread), everything else from any thread.

#include <atomic>
#include <cstdint>

#include "bridge/link_auth.hpp"

namespace tsmh::bridge {

/// The peer id of a goodbye: "this sender ends the session" (never a random id in practice).
inline constexpr std::uint64_t kSessionClosedPeer = ~std::uint64_t{0};
/// The peer id of a session in FAULT: "another session appeared here". Its
/// peer ends in FAULT too, and so does any session that hears it: two pairs
/// on one channel all stop, none takes over the other's slave.
inline constexpr std::uint64_t kSessionFaultPeer = ~std::uint64_t{0} - 1;

enum class SessionState : std::uint8_t {
  kOpen,    ///< not bound: waiting for a peer's handshake
  kBound,   ///< one peer; only its messages naming this end are used
  kClosed,  ///< the peer said goodbye (or fell silent) and this end does not re-arm
  kFault,   ///< another keyed sender appeared: the session is over for good
};

enum class SessionVerdict : std::uint8_t {
  kAccept,        ///< from the bound peer: use it
  kHandshake,     ///< part of binding: authentic, but its content is not used
  kOtherSession,  ///< another keyed sender; observe() has put the session in FAULT
  kEnded,         ///< the session is closed or in FAULT: nothing is used any more
};

struct SessionOptions {
  /// A bound peer heard from no more than this long ago is alive; a hello
  /// from anyone else meanwhile is a conflict. Also how long a candidate's
  /// hello holds the handshake for it.
  std::int64_t timeout_ns = 1'000'000'000;
  /// After the bound peer's goodbye, or its silence > timeout_ns, accept a new
  /// peer's handshake (a slave: a restarted master is served again). false
  /// (the server): the session ends there; a new peer needs a new process.
  bool rearm = false;
};

/// Why the session ended in FAULT (fault_sender() names who).
struct SessionFault {
  std::uint64_t sender_id = 0;  ///< the other sender (its trailer's id)
  std::uint64_t names = 0;      ///< the peer id it named (0: a hello)
};

class LinkSession {
 public:
  /// `signer` is this end's signer (it lives longer than the session): its
  /// sender id is this end's id, and set_peer_id() tells it whom to name.
  explicit LinkSession(MessageSigner& signer, SessionOptions options = {});
  LinkSession(const LinkSession&) = delete;
  LinkSession& operator=(const LinkSession&) = delete;

  /// Receive thread: one authenticated message's trailer, received at now_ns
  /// (CLOCK_MONOTONIC). No allocation, no lock.
  SessionVerdict observe(const AuthTrailer& t, std::int64_t now_ns) noexcept;
  /// Receive thread, periodically (the Receiver does it every 100 ms): a
  /// candidate silent for longer than the timeout is forgotten, and with
  /// rearm a bound peer silent that long ends the session (open again), so
  /// this end stops naming a process that is gone before anyone new arrives
  /// (a new peer would take that for another session).
  void tick(std::int64_t now_ns) noexcept;

  /// This end says goodbye: every message signed from now on names
  /// kSessionClosedPeer, and the peer's session ends when it gets one (a
  /// slave holds and re-arms; the server ends). Any thread; for a clean
  /// stop. A session in FAULT keeps naming kSessionFaultPeer instead.
  void close() noexcept;

  std::uint64_t my_id() const noexcept { return my_id_; }
  SessionState state() const noexcept { return state_.load(std::memory_order_acquire); }
  /// The bound peer's id; 0 while open.
  std::uint64_t peer() const noexcept { return peer_.load(std::memory_order_acquire); }
  /// Valid once state() is kFault.
  SessionFault fault() const noexcept {
    return {fault_sender_.load(std::memory_order_acquire),
            fault_names_.load(std::memory_order_acquire)};
  }
  /// Sessions bound so far (a slave that re-arms counts each master).
  std::uint64_t binds() const noexcept { return binds_.load(std::memory_order_relaxed); }
  /// Messages refused as another session's (each one; the first ends it).
  std::uint64_t other_session() const noexcept {
    return other_session_.load(std::memory_order_relaxed);
  }

 private:
  void bind(std::uint64_t peer, std::int64_t now_ns) noexcept;
  void reopen() noexcept;
  SessionVerdict conflict(const AuthTrailer& t) noexcept;
  void name(std::uint64_t peer) noexcept;

  MessageSigner& signer_;
  const std::uint64_t my_id_;
  const SessionOptions options_;
  std::atomic<SessionState> state_{SessionState::kOpen};
  std::atomic<std::uint64_t> peer_{0};
  std::atomic<std::uint64_t> fault_sender_{0};
  std::atomic<std::uint64_t> fault_names_{0};
  std::atomic<std::uint64_t> binds_{0};
  std::atomic<std::uint64_t> other_session_{0};
  std::atomic<bool> closing_{false};
  // Receive thread only.
  std::uint64_t candidate_ = 0;
  std::int64_t candidate_ns_ = 0;
  std::int64_t peer_heard_ns_ = 0;
  std::uint64_t gone_peer_ = 0;  // said goodbye: its late messages are refused, never rebound
};

/// "open", "bound", "closed", "FAULT".
const char* to_string(SessionState s) noexcept;

}  // namespace tsmh::bridge
