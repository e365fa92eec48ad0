// A repeating fault's log lines: the first, then at every tenfold of the count since the last.
#include <gtest/gtest.h>

#include <vector>

#include "drivers/tenfold_log.hpp"

TEST(TenfoldLog, TheFirstThenEveryTenfold) {
  rsd::drivers::TenfoldLog log;
  std::vector<uint64_t> said;
  for (uint64_t n = 0; n <= 2500; ++n)
    if (log.due(n)) said.push_back(n);
  EXPECT_EQ(said, (std::vector<uint64_t>{1, 10, 100, 1000}));
  rsd::drivers::TenfoldLog jumps;  // a count seen only now and then
  EXPECT_TRUE(jumps.due(7));
  EXPECT_FALSE(jumps.due(69));
  EXPECT_TRUE(jumps.due(75));
  EXPECT_FALSE(jumps.due(700));
  EXPECT_TRUE(jumps.due(750));
}
