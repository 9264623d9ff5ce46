// lcmtypes::MessageDecoder: every check from the raw bytes before lcm-gen
// may size anything, and no allocation at all while decoding (counted by
// replacing the global operator new in this test program).
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <random>
#include <stdexcept>
#include <string>

#include "corpus_messages.hpp"
#include "lcmtypes/message_decoder.hpp"

namespace {
// Allocations made by this thread while `counting` is set.
thread_local bool counting = false;
thread_local long allocations = 0;
}  // namespace

// GCC sees free() on what operator new returned; it is this pair's own malloc().
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  if (counting) ++allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
#pragma GCC diagnostic pop

namespace tsmh::lcmtypes {
namespace {

using test::Bytes;
using test::encoded;
using test::set_num_joints;

struct CountAllocations {
  CountAllocations() {
    allocations = 0;
    counting = true;
  }
  ~CountAllocations() { counting = false; }
  long count() const { return allocations; }
};

TEST(MessageDecoder, TheAllocationCounterCounts) {
  long allocs = 0;
  {
    const CountAllocations c;
    master_state_t fresh{};  // what lcm-gen's decode() does: resize to the claimed count
    fresh.q.resize(3);
    allocs = c.count();
  }
  EXPECT_EQ(allocs, 1);
}

template <class Message>
void expect_round_trips_without_allocating() {
  SCOPED_TRACE(Message::getTypeName());
  MessageDecoder<Message> d({1, 8});
  for (int n = 1; n <= 8; ++n) {
    const Bytes b = encoded<Message>(n, 100 + n);
    EXPECT_EQ(d.encoded_size(n), b.size());
    long allocs = 0;
    std::optional<DecodeError> error;
    {
      const CountAllocations c;
      error = d.decode(b.data(), b.size());
      allocs = c.count();
    }
    ASSERT_FALSE(error) << error->what.data();
    EXPECT_EQ(allocs, 0) << n << " joints";
    EXPECT_EQ(d.message().num_joints, n);
    EXPECT_EQ(d.message().seq, 100 + n);
    Bytes again(b.size());
    d.message().encode(again.data(), 0, static_cast<int>(again.size()));
    EXPECT_EQ(again, b);
  }
}

TEST(MessageDecoder, EveryTypeRoundTripsWithoutAllocating) {
  expect_round_trips_without_allocating<slave_state_t>();
  expect_round_trips_without_allocating<slave_truth_t>();
  expect_round_trips_without_allocating<master_command_t>();
  expect_round_trips_without_allocating<master_state_t>();
  expect_round_trips_without_allocating<master_force_t>();
  expect_round_trips_without_allocating<haptic_status_t>();
  expect_round_trips_without_allocating<calibration_request_t>();
}

// The raw checks rely on every message leading with utime, seq, num_joints.
template <class Message>
void expect_header_invariant() {
  SCOPED_TRACE(Message::getTypeName());
  const Bytes b = encoded<Message>(3, 77);
  WireHeader h;
  ASSERT_TRUE(read_header(b.data(), b.size(), h));
  EXPECT_EQ(h.hash, Message::getHash());
  EXPECT_EQ(h.utime, 1'700'000'000'000'000);
  EXPECT_EQ(h.seq, 77);
  EXPECT_EQ(h.num_joints, 3);
}

TEST(MessageDecoder, EveryMessageLeadsWithUtimeSeqNumJoints) {
  expect_header_invariant<slave_state_t>();
  expect_header_invariant<slave_truth_t>();
  expect_header_invariant<master_command_t>();
  expect_header_invariant<master_state_t>();
  expect_header_invariant<master_force_t>();
  expect_header_invariant<haptic_status_t>();
  expect_header_invariant<calibration_request_t>();
}

// The MASTER_STATE that crashed haptic-server's lcm driver: a 2-joint body
// whose num_joints says 2^28. lcm-gen's decode() alone resizes q and qd to
// 2^28 doubles (2 GiB each) before it finds the bytes missing.
TEST(MessageDecoder, TwoToThe28JointsIsRefusedWithoutAllocating) {
  MessageDecoder<master_state_t> d({2, 2});  // the lcm driver's range for a 2-DOF master
  Bytes b = encoded<master_state_t>(2, 9);
  set_num_joints(b, 1 << 28);
  std::optional<DecodeError> error;
  long allocs = 0;
  {
    const CountAllocations c;
    error = d.decode(b.data(), b.size());
    allocs = c.count();
  }
  ASSERT_TRUE(error);
  EXPECT_EQ(allocs, 0);
  EXPECT_EQ(error->fault, DecodeFault::kJointCount);
  EXPECT_EQ(error->num_joints, 1 << 28);
  EXPECT_EQ(error->seq, 9);
  EXPECT_STREQ(error->what.data(), "num_joints 268435456, expected 2");
  // The decoder still works afterwards.
  const Bytes good = encoded<master_state_t>(2, 10);
  EXPECT_FALSE(d.decode(good.data(), good.size()));
  EXPECT_EQ(d.message().seq, 10);
}

TEST(MessageDecoder, EachCheckNamesWhatWasWrong) {
  MessageDecoder<master_force_t> d({1, 8});
  const Bytes two = encoded<master_force_t>(2);
  auto what = [&](const Bytes& b) {
    const auto e = d.decode(b.data(), b.size());
    return e ? std::string(fault_name(e->fault)) + ": " + e->what.data() : std::string("ok");
  };
  EXPECT_EQ(what({}), "truncated_header: truncated: 0 bytes, the header needs 28");
  EXPECT_EQ(what(encoded<master_state_t>(2)),
            "type_hash: not a master_force_t (type hash differs)");
  Bytes minus = two;
  set_num_joints(minus, -1);
  EXPECT_EQ(what(minus), "joint_count: num_joints -1 outside 1..8");
  EXPECT_EQ(what(Bytes(two.begin(), two.end() - 1)),
            "size: truncated: 44 bytes, 45 expected for 2 joints");
  Bytes longer = two;
  longer.push_back(7);
  EXPECT_EQ(what(longer), "size: trailing bytes: 46 bytes, 45 expected for 2 joints");
  const auto e = d.decode(longer.data(), longer.size());
  ASSERT_TRUE(e);
  EXPECT_EQ(e->expected, 45u);
  EXPECT_EQ(e->size, 46u);
}

TEST(MessageDecoder, TrailingBytesAreLeftUnreadOnlyWhenAsked) {
  MessageDecoder<master_state_t> d({2, 2});
  Bytes signed_like = encoded<master_state_t>(2, 5);
  const std::size_t size = signed_like.size();
  signed_like.resize(size + 64, 0xAB);  // another peer's MAC trailer
  EXPECT_TRUE(d.decode(signed_like.data(), signed_like.size(), Trailing::kReject));
  ASSERT_FALSE(d.decode(signed_like.data(), signed_like.size(), Trailing::kIgnore));
  EXPECT_EQ(d.message().seq, 5);
  // Ignoring what follows never excuses what is missing.
  EXPECT_TRUE(d.decode(signed_like.data(), size - 1, Trailing::kIgnore));
  Bytes huge = signed_like;
  set_num_joints(huge, 1 << 28);
  EXPECT_TRUE(d.decode(huge.data(), huge.size(), Trailing::kIgnore));
}

TEST(MessageDecoder, RandomBytesAndRandomLengthsNeverCrashOrAllocate) {
  MessageDecoder<slave_state_t> d({1, 8});
  const Bytes good = encoded<slave_state_t>(4);
  std::mt19937 rng(11);
  long allocs = 0;
  int accepted = 0;
  for (int i = 0; i < 20000; ++i) {
    Bytes b = i % 2 ? good : Bytes(rng() % 400);
    if (i % 2) {
      b[rng() % b.size()] = static_cast<std::uint8_t>(rng());  // one random byte anywhere
      if (rng() % 4 == 0) set_num_joints(b, static_cast<std::int32_t>(rng()));
    } else {
      for (auto& x : b)
        x = static_cast<std::uint8_t>(rng());
    }
    const CountAllocations c;
    if (!d.decode(b.data(), b.size())) ++accepted;
    allocs += c.count();
  }
  EXPECT_EQ(allocs, 0);
  EXPECT_GT(accepted, 1000) << "a byte changed in a double's payload still decodes";
}

TEST(MessageDecoder, RefusesARangeItCannotHold) {
  EXPECT_THROW(MessageDecoder<slave_state_t>({3, 2}), std::invalid_argument);
  EXPECT_THROW(MessageDecoder<slave_state_t>({-1, 2}), std::invalid_argument);
  EXPECT_THROW(MessageDecoder<slave_state_t>({1, 1 << 20}), std::invalid_argument);
  EXPECT_NO_THROW(MessageDecoder<slave_state_t>({0, 0}));
}

}  // namespace
}  // namespace tsmh::lcmtypes
