// Absolute deadlines and how the schedule re-bases after an overrun.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "realtime/pacing.hpp"

namespace tsmh::realtime {
namespace {

TEST(TickSchedule, AbsoluteDeadlinesReBaseOnOverrun) {
  constexpr std::int64_t P = 1'000'000;
  EXPECT_EQ(next_tick(10 * P, 10 * P + 300'000, P).deadline_ns, 11 * P);
  EXPECT_EQ(next_tick(10 * P, 10 * P + 300'000, P).skipped, 0);
  // Finished 2.5 periods late: deadlines 11 and 12 are skipped, next is 13.
  const auto late = next_tick(10 * P, 12 * P + P / 2, P);
  EXPECT_EQ(late.deadline_ns, 13 * P);
  EXPECT_EQ(late.skipped, 2);
  // ...but the tick at 13 is late against 11, the first deadline not run: a
  // stall is measured at its full length, not as the miss of the re-based one.
  EXPECT_EQ(late.due_ns, 11 * P);
  EXPECT_EQ(next_tick(10 * P, 10 * P + 300'000, P).due_ns, 11 * P);
  // Exactly at the next deadline counts as missed (no zero-length sleep burst).
  EXPECT_EQ(next_tick(10 * P, 11 * P, P).deadline_ns, 12 * P);
}

// The Pacer carries the schedule between ticks: on the grid, skips counted,
// lateness measured against the first deadline that did not run.
TEST(Pacer, FollowsTheGridAndCountsSkippedDeadlines) {
  constexpr std::int64_t P = 1'000'000;
  Pacer pace(P, 10 * P);
  EXPECT_EQ(pace.deadline_ns(), 10 * P);
  EXPECT_EQ(pace.advance(10 * P + 300'000), 0);
  EXPECT_EQ(pace.deadline_ns(), 11 * P);
  EXPECT_EQ(pace.due_ns(), 11 * P);
  // A tick that ends 2.5 periods late: 12 and 13 are skipped, the next runs
  // at 14 and reports its lateness against 12.
  EXPECT_EQ(pace.advance(13 * P + P / 2), 2);
  EXPECT_EQ(pace.deadline_ns(), 14 * P);
  EXPECT_EQ(pace.due_ns(), 12 * P);
  EXPECT_EQ(pace.advance(14 * P + 1), 0);
  EXPECT_EQ(pace.deadline_ns(), 15 * P);
  EXPECT_EQ(pace.due_ns(), 15 * P);
}

// A stand-in for hardware runs every period: no skip, whatever the time.
TEST(Pacer, AdvanceEveryKeepsEveryDeadline) {
  constexpr std::int64_t P = 1'000'000;
  Pacer pace(P, 10 * P);
  pace.advance_every();
  pace.advance_every();
  EXPECT_EQ(pace.deadline_ns(), 12 * P);
  EXPECT_EQ(pace.due_ns(), 12 * P);
}

TEST(Pacer, WaitSleepsToTheAbsoluteDeadline) {
  constexpr std::int64_t P = 2'000'000;
  Pacer pace(P, monotonic_now_ns() + P);
  for (int i = 0; i < 3; ++i) {
    pace.wait_through_signals();
    EXPECT_GE(monotonic_now_ns(), pace.deadline_ns());
    pace.advance(monotonic_now_ns());
  }
}

}  // namespace
}  // namespace tsmh::realtime
