// NodeInbox (bridge/node_inbox.hpp): what a standalone node does with a raw
// buffer, in order: MAC, session, the checked decoder. Pure logic on bytes
// as LCM would hand them over; no LCM started.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <string>
#include <tsmh/master_command_t.hpp>
#include <vector>

#include "bridge/link_auth.hpp"
#include "bridge/node_inbox.hpp"
#include "realtime/clock.hpp"

namespace tsmh::bridge {
namespace {

const char* const kChannel = "MASTER_COMMAND";

std::vector<std::uint8_t> encode(int joints, std::int64_t seq) {
  master_command_t m;
  m.utime = 1;
  m.seq = seq;
  m.num_joints = joints;
  m.position_ref.assign(static_cast<std::size_t>(joints), 0.25);
  m.enable = true;
  m.clutch = false;
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

/// `payload` with a trailer from `signer` naming `peer` (0: a hello).
std::vector<std::uint8_t> signed_by(const MessageSigner& signer, std::uint64_t seq,
                                    std::uint64_t peer, std::vector<std::uint8_t> payload) {
  const std::size_t size = payload.size();
  payload.resize(size + kAuthTrailerBytes);
  signer.sign_as(kChannel, payload.data(), size,
                 {signer.sender_id(), seq, realtime::wall_clock_utime(), peer},
                 payload.data() + size);
  return payload;
}

TEST(NodeInbox, UnkeyedDecodesOnlyTheNodesJointCount) {
  const NodeLink link;  // no key: no verifier, no session
  NodeInbox<master_command_t> inbox(link, 2);
  const auto good = encode(2, 7);
  const auto* msg = inbox.receive(good.data(), good.size(), kChannel);
  ASSERT_NE(msg, nullptr);
  EXPECT_EQ(msg->seq, 7);
  EXPECT_EQ(msg->position_ref[1], 0.25);
  const auto three = encode(3, 8);
  EXPECT_EQ(inbox.receive(three.data(), three.size(), kChannel), nullptr);
  EXPECT_EQ(inbox.rejected(), 1);
  EXPECT_NE(std::string(inbox.last_rejection()).find("num_joints 3"), std::string::npos)
      << inbox.last_rejection();
  const auto cut = std::vector<std::uint8_t>(good.begin(), good.begin() + 10);
  EXPECT_EQ(inbox.receive(cut.data(), cut.size(), kChannel), nullptr);
  EXPECT_EQ(inbox.rejected(), 2);
  // The node's own checks after decoding count in the same place.
  inbox.reject("position_ref is not finite");
  EXPECT_EQ(inbox.rejected(), 3);
  EXPECT_STREQ(inbox.last_rejection(), "position_ref is not finite");
}

TEST(NodeInbox, KeyedUsesOnlyTheBoundPeersAuthenticMessages) {
  const auto key = std::make_shared<const LinkKey>(LinkKey::generate());
  NodeLink link;
  link.signer = std::make_unique<MessageSigner>(key);
  link.verifier = std::make_unique<MessageVerifier>(key);
  link.session = std::make_unique<LinkSession>(*link.signer, SessionOptions{.rearm = true});
  NodeInbox<master_command_t> inbox(link, 2);
  const MessageSigner server(key);
  const std::uint64_t me = link.signer->sender_id();

  // Unsigned, or signed with another key: never decoded.
  const auto plain = encode(2, 1);
  EXPECT_EQ(inbox.receive(plain.data(), plain.size(), kChannel), nullptr);
  const MessageSigner stranger(std::make_shared<const LinkKey>(LinkKey::generate()));
  const auto forged = signed_by(stranger, 1, me, encode(2, 1));
  EXPECT_EQ(inbox.receive(forged.data(), forged.size(), kChannel), nullptr);
  EXPECT_EQ(inbox.unauthentic(), 2);

  // The server's hello binds nothing and its content is unused.
  const auto hello = signed_by(server, 1, 0, encode(2, 1));
  EXPECT_EQ(inbox.receive(hello.data(), hello.size(), kChannel), nullptr);
  // Naming this node: bound, used.
  const auto answer = signed_by(server, 2, me, encode(2, 2));
  const auto* msg = inbox.receive(answer.data(), answer.size(), kChannel);
  ASSERT_NE(msg, nullptr);
  EXPECT_EQ(msg->seq, 2);
  EXPECT_EQ(link.session->state(), SessionState::kBound);

  // A second keyed server: refused, and the session ends in FAULT.
  const MessageSigner second(key);
  const auto other = signed_by(second, 1, me, encode(2, 3));
  EXPECT_EQ(inbox.receive(other.data(), other.size(), kChannel), nullptr);
  EXPECT_EQ(inbox.other_session(), 1);
  EXPECT_EQ(link.session->state(), SessionState::kFault);
  const auto late = signed_by(server, 3, me, encode(2, 4));
  EXPECT_EQ(inbox.receive(late.data(), late.size(), kChannel), nullptr);
  EXPECT_EQ(inbox.rejected(), 0) << "nothing above reached the decoder's refusal";
}

TEST(NodeInbox, KeyedRefusesAPayloadLongerThanTheMessage) {
  const auto key = std::make_shared<const LinkKey>(LinkKey::generate());
  NodeLink link;
  link.signer = std::make_unique<MessageSigner>(key);
  link.verifier = std::make_unique<MessageVerifier>(key);
  link.session = std::make_unique<LinkSession>(*link.signer, SessionOptions{.rearm = true});
  NodeInbox<master_command_t> inbox(link, 2);
  const MessageSigner server(key);
  auto padded = encode(2, 2);
  padded.push_back(0);  // a signed payload must be exactly the message
  const auto m = signed_by(server, 2, link.signer->sender_id(), padded);
  EXPECT_EQ(inbox.receive(m.data(), m.size(), kChannel), nullptr);
  EXPECT_EQ(inbox.rejected(), 1);
}

}  // namespace
}  // namespace tsmh::bridge
