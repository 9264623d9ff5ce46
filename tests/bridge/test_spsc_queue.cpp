#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

#include "bridge/spsc_queue.hpp"

namespace tsmh::bridge {
namespace {

TEST(SpscQueue, FifoAndRefusesWhenFull) {
  SpscQueue<int, 4> q;
  int v = 0;
  EXPECT_FALSE(q.pop(v));
  for (int i = 0; i < 4; ++i)
    EXPECT_TRUE(q.push(i));
  EXPECT_FALSE(q.push(99)) << "full: push must fail, not overwrite or wait";
  EXPECT_EQ(q.size(), 4U);
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(q.pop(v));
    EXPECT_EQ(v, i);
  }
  EXPECT_FALSE(q.pop(v));
  EXPECT_TRUE(q.push(5)) << "space is reusable after popping";
}

TEST(SpscQueue, TwoThreadsTransferEverythingInOrder) {
  SpscQueue<std::uint64_t, 64> q;
  constexpr std::uint64_t kCount = 500'000;
  std::uint64_t out_of_order = 0, received = 0;
  std::thread consumer([&] {
    std::uint64_t expected = 0, v = 0;
    while (expected < kCount) {
      if (!q.pop(v)) continue;
      if (v != expected) ++out_of_order;
      expected = v + 1;
      ++received;
    }
  });
  for (std::uint64_t i = 0; i < kCount;)
    if (q.push(i)) ++i;
  consumer.join();
  EXPECT_EQ(received, kCount);
  EXPECT_EQ(out_of_order, 0U);
}

}  // namespace
}  // namespace tsmh::bridge
