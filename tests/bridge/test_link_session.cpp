// LinkSession (bridge/link_session.hpp): the handshake, one peer per
// session, the end in FAULT on any other keyed sender, goodbye and re-arm,
// and replays of an older session into a restarted receiver. Pure logic:
// trailers as a verifier would hand them over, times given by the test.
#include <gtest/gtest.h>

#include <memory>

#include "bridge/link_auth.hpp"
#include "bridge/link_session.hpp"

namespace tsmh::bridge {
namespace {

constexpr std::int64_t kMs = 1'000'000;

std::shared_ptr<const LinkKey> key() {
  static const auto k = std::make_shared<const LinkKey>(LinkKey::generate());
  return k;
}

/// One end of a link: its signer and session.
struct End {
  explicit End(SessionOptions o = {}) : signer(key()), session(signer, o) {}
  /// The trailer of the next message this end publishes.
  AuthTrailer next() { return {signer.sender_id(), ++seq, 0, signer.peer_id()}; }
  MessageSigner signer;
  LinkSession session;
  std::uint64_t seq = 0;
};

TEST(LinkSession, HandshakeBindsBothEndsAndOnlyTheBoundPeerIsUsed) {
  End server;                  // receives SLAVE_STATE
  End slave({.rearm = true});  // receives MASTER_COMMAND
  EXPECT_EQ(server.signer.peer_id(), 0U) << "unbound: names nobody";
  // Both publish from the start. The slave's first state is a hello.
  EXPECT_EQ(server.session.observe(slave.next(), 0), SessionVerdict::kHandshake);
  EXPECT_EQ(server.signer.peer_id(), slave.signer.sender_id()) << "answers the candidate";
  EXPECT_EQ(server.session.state(), SessionState::kOpen);
  // The server's next command names the slave: the slave binds and uses it.
  EXPECT_EQ(slave.session.observe(server.next(), kMs), SessionVerdict::kAccept);
  EXPECT_EQ(slave.session.state(), SessionState::kBound);
  EXPECT_EQ(slave.session.peer(), server.signer.sender_id());
  EXPECT_EQ(slave.signer.peer_id(), server.signer.sender_id());
  // The slave's next state names the server: bound both ways.
  EXPECT_EQ(server.session.observe(slave.next(), 2 * kMs), SessionVerdict::kAccept);
  EXPECT_EQ(server.session.state(), SessionState::kBound);
  EXPECT_EQ(server.session.binds(), 1U);
  for (int i = 0; i < 100; ++i) {
    EXPECT_EQ(server.session.observe(slave.next(), (3 + i) * kMs), SessionVerdict::kAccept);
    EXPECT_EQ(slave.session.observe(server.next(), (3 + i) * kMs), SessionVerdict::kAccept);
  }
}

TEST(LinkSession, AHelloStillInFlightFromTheBoundPeerIsNotUsedAndEndsNothing) {
  End server, slave({.rearm = true});
  const AuthTrailer early = slave.next();  // a hello, delayed on the way
  server.session.observe(slave.next(), 0);
  slave.session.observe(server.next(), 0);
  EXPECT_EQ(server.session.observe(slave.next(), 0), SessionVerdict::kAccept);
  EXPECT_EQ(server.session.observe(early, 0), SessionVerdict::kHandshake);
  EXPECT_EQ(server.session.state(), SessionState::kBound);
}

TEST(LinkSession, ASecondKeyedSenderJoiningEndsTheSessionInFault) {
  End server, slave({.rearm = true}), intruder({.rearm = true});
  server.session.observe(slave.next(), 0);
  slave.session.observe(server.next(), 0);
  server.session.observe(slave.next(), 0);
  ASSERT_EQ(server.session.state(), SessionState::kBound);
  // A second virtual-slave with the key says hello.
  const AuthTrailer hello = intruder.next();
  EXPECT_EQ(server.session.observe(hello, kMs), SessionVerdict::kOtherSession);
  EXPECT_EQ(server.session.state(), SessionState::kFault);
  EXPECT_EQ(server.session.fault().sender_id, intruder.signer.sender_id());
  EXPECT_EQ(server.session.fault().names, 0U);
  EXPECT_EQ(server.signer.peer_id(), kSessionFaultPeer) << "says so: the slave's session ends too";
  // Nothing is used after: not even the former peer's messages.
  EXPECT_EQ(server.session.observe(slave.next(), kMs), SessionVerdict::kEnded);
  EXPECT_EQ(server.session.observe(intruder.next(), kMs), SessionVerdict::kEnded);
  EXPECT_EQ(server.session.other_session(), 2U);
  // The former peer hears that its master's session is in FAULT: FAULT too,
  // and it never serves the next master as if nothing had happened.
  EXPECT_EQ(slave.session.observe(server.next(), kMs), SessionVerdict::kOtherSession);
  EXPECT_EQ(slave.session.state(), SessionState::kFault);
  // Stopping after a FAULT is no goodbye: the marker stays.
  server.session.close();
  EXPECT_EQ(server.signer.peer_id(), kSessionFaultPeer);
  // An open session that hears a session in FAULT on its channel: FAULT too.
  End newcomer({.rearm = true});
  EXPECT_EQ(newcomer.session.observe(server.next(), kMs), SessionVerdict::kOtherSession);
  EXPECT_EQ(newcomer.session.state(), SessionState::kFault);
}

TEST(LinkSession, TwoPairsOnOneChannelEndBothSessions) {
  // Pair A is bound; pair B starts on the same channel with the same key.
  End server_a, slave_a({.rearm = true}), server_b, slave_b({.rearm = true});
  server_a.session.observe(slave_a.next(), 0);
  slave_a.session.observe(server_a.next(), 0);
  server_a.session.observe(slave_a.next(), 0);
  // Every receiver hears the other pair. Pair B's ends hear pair A's bound
  // traffic: it names another id, which never binds, even an open session.
  EXPECT_EQ(server_b.session.observe(slave_a.next(), kMs), SessionVerdict::kOtherSession);
  EXPECT_EQ(slave_b.session.observe(server_a.next(), kMs), SessionVerdict::kOtherSession);
  // Pair A's ends hear pair B's hellos: a second keyed sender.
  EXPECT_EQ(slave_a.session.observe(server_b.next(), kMs), SessionVerdict::kOtherSession);
  EXPECT_EQ(server_a.session.observe(slave_b.next(), kMs), SessionVerdict::kOtherSession);
  for (End* e : {&server_a, &slave_a, &server_b, &slave_b})
    EXPECT_EQ(e->session.state(), SessionState::kFault);
}

TEST(LinkSession, TwoLiveHellosToAnOpenEndAreAConflict) {
  End server, slave1, slave2;
  EXPECT_EQ(server.session.observe(slave1.next(), 0), SessionVerdict::kHandshake);
  EXPECT_EQ(server.session.observe(slave2.next(), 10 * kMs), SessionVerdict::kOtherSession);
  EXPECT_EQ(server.session.state(), SessionState::kFault);
  // A candidate silent for longer than the timeout is no longer one.
  End server2, gone, next;
  server2.session.observe(gone.next(), 0);
  EXPECT_EQ(server2.session.observe(next.next(), 2000 * kMs), SessionVerdict::kHandshake);
  EXPECT_EQ(server2.signer.peer_id(), next.signer.sender_id());
}

TEST(LinkSession, AReplayOfAnOlderSessionIntoARestartedReceiverMovesNothing) {
  End server, old_slave({.rearm = true});
  server.session.observe(old_slave.next(), 0);
  old_slave.session.observe(server.next(), 0);
  server.session.observe(old_slave.next(), 0);
  // Commands recorded from that session name the old slave's id...
  const AuthTrailer recorded = server.next();
  ASSERT_EQ(recorded.peer_id, old_slave.signer.sender_id());
  // ...and the restarted slave has a new random id (its nonce): never bound, FAULT.
  End restarted({.rearm = true});
  EXPECT_EQ(restarted.session.observe(recorded, 0), SessionVerdict::kOtherSession);
  EXPECT_EQ(restarted.session.peer(), 0U);
  EXPECT_EQ(restarted.session.state(), SessionState::kFault);
  // Also the recorded hello of the server (it named nobody yet) binds nothing:
  // it is a hello, whose content is never used.
  End restarted2({.rearm = true});
  EXPECT_EQ(restarted2.session.observe({server.signer.sender_id(), 1, 0, 0}, 0),
            SessionVerdict::kHandshake);
  EXPECT_EQ(restarted2.session.state(), SessionState::kOpen);
}

TEST(LinkSession, GoodbyeHandsTheSlaveOverToTheNextMasterAndEndsTheServersSession) {
  End server1, slave({.rearm = true});
  slave.session.observe(server1.next(), 0);
  server1.session.observe(slave.next(), 0);
  slave.session.observe(server1.next(), 0);
  server1.session.observe(slave.next(), 0);
  ASSERT_EQ(slave.session.state(), SessionState::kBound);
  const AuthTrailer late = server1.next();  // overtaken on the way by the goodbye
  server1.session.close();
  EXPECT_EQ(server1.signer.peer_id(), kSessionClosedPeer);
  EXPECT_EQ(slave.session.observe(server1.next(), kMs), SessionVerdict::kAccept)
      << "the goodbye's content (a hold) is used";
  EXPECT_EQ(slave.session.state(), SessionState::kOpen) << "a slave re-arms";
  EXPECT_EQ(slave.signer.peer_id(), 0U);
  EXPECT_EQ(slave.session.observe(late, kMs), SessionVerdict::kEnded)
      << "the old master never binds again";
  // A new server process: the handshake again, no fault.
  End server2;
  EXPECT_EQ(slave.session.observe(server2.next(), 2 * kMs), SessionVerdict::kHandshake);
  server2.session.observe(slave.next(), 2 * kMs);
  EXPECT_EQ(slave.session.observe(server2.next(), 3 * kMs), SessionVerdict::kAccept);
  EXPECT_EQ(slave.session.binds(), 2U);

  // The server does not re-arm: after its slave's goodbye anyone else is a conflict.
  End server, slave1({.rearm = true}), slave2({.rearm = true});
  server.session.observe(slave1.next(), 0);
  slave1.session.observe(server.next(), 0);
  server.session.observe(slave1.next(), 0);
  slave1.session.close();
  EXPECT_EQ(server.session.observe(slave1.next(), kMs), SessionVerdict::kAccept);
  EXPECT_EQ(server.session.state(), SessionState::kClosed);
  EXPECT_EQ(server.session.observe(slave2.next(), 5000 * kMs), SessionVerdict::kOtherSession);
  EXPECT_EQ(server.session.state(), SessionState::kFault);
}

TEST(LinkSession, AGoodbyeFromAnyoneButThePeerChangesNothing) {
  End server, slave({.rearm = true}), other;
  slave.session.observe(server.next(), 0);
  server.session.observe(slave.next(), 0);
  slave.session.observe(server.next(), 0);
  other.session.close();
  EXPECT_EQ(slave.session.observe(other.next(), kMs), SessionVerdict::kEnded);
  EXPECT_EQ(slave.session.state(), SessionState::kBound);
  EXPECT_EQ(slave.session.observe(server.next(), kMs), SessionVerdict::kAccept);
}

TEST(LinkSession, ASlaveReArmsAfterItsMasterWasSilentLongerThanTheTimeout) {
  const SessionOptions slave_options{.timeout_ns = 500 * kMs, .rearm = true};
  End server1, slave(slave_options), server2;
  slave.session.observe(server1.next(), 0);
  server1.session.observe(slave.next(), 0);
  slave.session.observe(server1.next(), 10 * kMs);
  ASSERT_EQ(slave.session.state(), SessionState::kBound);
  // 400 ms after the last command a new master is another session...
  End slave_b(slave_options), server1_b;
  slave_b.session.observe(server1_b.next(), 0);
  server1_b.session.observe(slave_b.next(), 0);
  slave_b.session.observe(server1_b.next(), 10 * kMs);
  ASSERT_EQ(slave_b.session.state(), SessionState::kBound);
  EXPECT_EQ(slave_b.session.observe(server2.next(), 410 * kMs), SessionVerdict::kOtherSession);
  // ...more than 500 ms after it, the handshake with the new master.
  EXPECT_EQ(slave.session.observe(server2.next(), 520 * kMs), SessionVerdict::kHandshake);
  EXPECT_EQ(slave.session.state(), SessionState::kOpen);
  EXPECT_EQ(slave.signer.peer_id(), server2.signer.sender_id());
}

TEST(LinkSession, TheServerStaysBoundThroughItsSlavesSilence) {
  End server, slave({.rearm = true}), newcomer;
  server.session.observe(slave.next(), 0);
  slave.session.observe(server.next(), 0);
  server.session.observe(slave.next(), 0);
  // 10 s of silence (a network outage): the same slave is used again...
  EXPECT_EQ(server.session.observe(slave.next(), 10'000 * kMs), SessionVerdict::kAccept);
  // ...another never: a new slave needs a new server process.
  EXPECT_EQ(server.session.observe(newcomer.next(), 20'000 * kMs), SessionVerdict::kOtherSession);
}

}  // namespace
}  // namespace tsmh::bridge
