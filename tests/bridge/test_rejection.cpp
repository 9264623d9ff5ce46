// Every reason a message is refused has its name (the counters' keys) and a
// description that names the channel, the field and the value.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "bridge/rejection.hpp"

namespace tsmh::bridge {
namespace {

struct Expected {
  RejectReason reason;
  const char* name;
  const char* text;  // describe() of make_rejection(reason, "x_in", 2.5, 1) with seq 7 on "C"
};

TEST(Rejection, EveryReasonHasItsNameAndDescription) {
  const std::vector<Expected> all = {
      {RejectReason::kDecode, "decode", "C seq 7: cannot decode: x_in[1]"},
      {RejectReason::kJointCount, "joint_count", "C seq 7: joint count 2.5 rejected (x_in[1])"},
      {RejectReason::kNonFinite, "non_finite", "C seq 7: x_in[1] = 2.5 is not finite"},
      {RejectReason::kOutOfRange, "out_of_range",
       "C seq 7: x_in[1] = 2.5 is outside its configured range"},
      {RejectReason::kTimeBackwards, "time_backwards",
       "C seq 7: utime 2.5 us is not after the previous message's (x_in[1])"},
      {RejectReason::kImplausible, "implausible_step",
       "C seq 7: x_in[1] stepped by 2.5 since the last accepted sample: faster than its "
       "configured limit"},
      {RejectReason::kUnauthenticated, "unauthenticated",
       "C seq 7: not authenticated (a sender without the link key, or too old a program): "
       "x_in[1]"},
      {RejectReason::kBadMac, "bad_mac",
       "C seq 7: MAC does not match (wrong link key, or altered on the way): x_in[1]"},
      {RejectReason::kStale, "stale",
       "C seq 7: sent 2.5 us from this host's clock, outside the freshness window (a "
       "recording, or clocks not synchronised): x_in[1]"},
      {RejectReason::kReplayed, "replayed",
       "C seq 7: replayed: x_in[1] already seen or older than the replay window"},
      {RejectReason::kOtherSession, "other_session",
       "C seq 7: another session (a second keyed sender on this session's channel, a restarted "
       "peer or a replay of an older session): x_in[1]; the session ends in FAULT"},
      {RejectReason::kSessionEnded, "session_ended", "C seq 7: the session has ended: x_in[1]"},
  };
  ASSERT_EQ(all.size(), static_cast<std::size_t>(kRejectReasons));
  for (const Expected& e : all) {
    Rejection r = make_rejection(e.reason, "x_in", 2.5, 1);
    r.seq = 7;
    EXPECT_EQ(reason_name(e.reason), e.name);
    EXPECT_EQ(describe(r, "C"), e.text) << e.name;
  }
}

TEST(Rejection, AFieldWithoutJointOrSeqIsDescribedWithoutThem) {
  const Rejection r = make_rejection(RejectReason::kNonFinite, "radius_m", -1.0);
  EXPECT_EQ(describe(r, "ARM1_SLAVE_STATE"), "ARM1_SLAVE_STATE: radius_m = -1 is not finite");
}

TEST(Rejection, AReasonOutsideTheEnumIsNamedUnknown) {
  const auto bad = static_cast<RejectReason>(kRejectReasons);
  EXPECT_EQ(reason_name(bad), "unknown");
  EXPECT_EQ(describe(make_rejection(bad, "x_in"), "C"), "C: ");
}

}  // namespace
}  // namespace tsmh::bridge
