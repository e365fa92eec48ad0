// The lock-free hand-over between pipeline threads: under a producer that never waits and a
// slow consumer, every slot index comes out exactly once — popped by the consumer or taken
// back (dropped) by the producer — and order is kept.
#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "daemon/drop_oldest_queue.hpp"

using rsd::daemon::DropOldestQueue;

TEST(DropOldestQueue, FifoAndFull) {
  DropOldestQueue q(3);
  EXPECT_TRUE(q.push(1));
  EXPECT_TRUE(q.push(2));
  EXPECT_TRUE(q.push(3));
  EXPECT_FALSE(q.push(4));
  EXPECT_EQ(q.reclaim_oldest(), 1u);  // the producer drops the oldest
  EXPECT_TRUE(q.push(4));
  EXPECT_EQ(q.pop(), 2u);
  EXPECT_EQ(q.pop(), 3u);
  EXPECT_EQ(q.pop(), 4u);
  EXPECT_FALSE(q.pop().has_value());
  EXPECT_EQ(q.size(), 0u);
}

TEST(DropOldestQueue, ConcurrentProducerDropsConsumerPopsEachExactlyOnce) {
  constexpr uint32_t kItems = 200000;
  DropOldestQueue q(4);
  std::vector<uint32_t> popped, dropped;
  popped.reserve(kItems);
  dropped.reserve(kItems);
  std::atomic<bool> done{false};
  std::thread consumer([&] {
    for (;;) {
      if (auto v = q.pop()) {
        popped.push_back(*v);
        if (v.value() % 7 == 0) std::this_thread::yield();  // a consumer that falls behind
      } else if (done.load()) {
        if (auto w = q.pop()) popped.push_back(*w);
        else break;
      }
    }
  });
  for (uint32_t i = 0; i < kItems; ++i)
    while (!q.push(i))
      if (auto old = q.reclaim_oldest()) dropped.push_back(*old);
  done = true;
  consumer.join();
  std::vector<int> seen(kItems, 0);
  for (uint32_t v : popped) ++seen[v];
  for (uint32_t v : dropped) ++seen[v];
  for (uint32_t i = 0; i < kItems; ++i) ASSERT_EQ(seen[i], 1) << i;
  for (size_t i = 1; i < popped.size(); ++i) ASSERT_LT(popped[i - 1], popped[i]);  // order kept
  EXPECT_GT(dropped.size(), 0u);  // the test did exercise dropping
  EXPECT_GT(popped.size(), 0u);
}
