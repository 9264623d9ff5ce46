// Absolute deadlines and how the schedule re-bases after an overrun.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "haptics/tick_schedule.hpp"

namespace tsmh::haptics {
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

}  // namespace
}  // namespace tsmh::haptics
