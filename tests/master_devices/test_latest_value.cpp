#include <gtest/gtest.h>

#include <thread>

#include "master_devices/latest_value.hpp"

namespace tsmh::master_devices {
namespace {

struct Sample {
  std::uint64_t seq = 0;
  std::uint64_t twice = 0;  // always 2 * seq: a torn copy breaks it
  double filler[8] = {};
};

TEST(LatestValue, FetchBeforePublishIsInitialAndNotFresh) {
  LatestValue<int> cell(7);
  int v = 0;
  EXPECT_FALSE(cell.fetch(v));
  EXPECT_EQ(v, 7);
}

TEST(LatestValue, FreshOncePerPublishAndNewestWins) {
  LatestValue<int> cell;
  int v = 0;
  cell.publish(1);
  cell.publish(2);
  cell.publish(3);
  EXPECT_TRUE(cell.fetch(v));
  EXPECT_EQ(v, 3);
  EXPECT_FALSE(cell.fetch(v));
  EXPECT_EQ(v, 3);
  cell.publish(4);
  EXPECT_TRUE(cell.fetch(v));
  EXPECT_EQ(v, 4);
}

TEST(LatestValue, ConcurrentReaderNeverSeesTornOrOlderValues) {
  LatestValue<Sample> cell;
  constexpr std::uint64_t kCount = 200000;
  std::thread writer([&] {
    for (std::uint64_t i = 1; i <= kCount; ++i) {
      Sample s;
      s.seq = i;
      s.twice = 2 * i;
      cell.publish(s);
    }
  });
  std::uint64_t last = 0;
  std::uint64_t fresh = 0;
  bool consistent = true;
  bool monotonic = true;
  while (last < kCount) {
    Sample s;
    if (cell.fetch(s)) ++fresh;
    consistent = consistent && s.twice == 2 * s.seq;
    monotonic = monotonic && s.seq >= last;
    last = s.seq;
  }
  writer.join();
  Sample final_value;
  cell.fetch(final_value);
  EXPECT_TRUE(consistent);
  EXPECT_TRUE(monotonic);
  EXPECT_EQ(final_value.seq, kCount);
  EXPECT_GT(fresh, 0u);
}

}  // namespace
}  // namespace tsmh::master_devices
