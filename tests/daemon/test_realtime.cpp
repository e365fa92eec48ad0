// Real-time scheduling of the pipeline's threads (daemon/realtime.hpp), checked against what
// the kernel reports afterwards (pthread_getschedparam, pthread_getaffinity_np,
// /proc/self/status): each step is done when permitted and said when not, never half-done.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>

#include <fstream>
#include <string>
#include <thread>

#include "daemon/realtime.hpp"
#include "tests/support/sanitizer.hpp"

using rsd::daemon::lock_memory;
using rsd::daemon::make_thread_realtime;

namespace {

struct Sched {
  int policy = -1, priority = -1;
};

Sched sched_of_this_thread() {
  Sched s;
  sched_param p{};
  pthread_getschedparam(pthread_self(), &s.policy, &p);
  s.priority = p.sched_priority;
  return s;
}

// Runs `f` on a fresh thread (so that the test's own thread keeps its scheduling).
template <class F>
void on_a_thread(F f) {
  std::thread t(f);
  t.join();
}

long locked_kb() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmLck:", 0) == 0) return std::stol(line.substr(6));
  return -1;
}

}  // namespace

TEST(Realtime, NothingAskedNothingChanged) {
  on_a_thread([] {
    const Sched before = sched_of_this_thread();
    EXPECT_EQ(make_thread_realtime("capture", 0, -1), "");
    const Sched after = sched_of_this_thread();
    EXPECT_EQ(after.policy, before.policy);
    EXPECT_EQ(after.priority, before.priority);
  });
}

TEST(Realtime, FifoExactlyWhenItSaysSo) {
  on_a_thread([] {
    const std::string why = make_thread_realtime("capture", 10, -1);
    const Sched s = sched_of_this_thread();
    if (why.empty()) {
      EXPECT_EQ(s.policy, SCHED_FIFO);
      EXPECT_EQ(s.priority, 10);
    } else {
      EXPECT_NE(why.find("not permitted"), std::string::npos) << why;
      EXPECT_EQ(s.policy, SCHED_OTHER) << why;
    }
  });
}

TEST(Realtime, AnImpossiblePriorityIsSaidAndTheThreadRunsOn) {
  on_a_thread([] {
    const std::string why = make_thread_realtime("capture", 200, -1);
    EXPECT_NE(why.find("the capture thread stays at normal priority"), std::string::npos) << why;
    EXPECT_EQ(sched_of_this_thread().policy, SCHED_OTHER);
  });
}

TEST(Realtime, PinnedToTheCpuItNames) {
  on_a_thread([] {
    EXPECT_EQ(make_thread_realtime("rectify", 0, 0), "");
    cpu_set_t set;
    CPU_ZERO(&set);
    ASSERT_EQ(pthread_getaffinity_np(pthread_self(), sizeof set, &set), 0);
    EXPECT_EQ(CPU_COUNT(&set), 1);
    EXPECT_TRUE(CPU_ISSET(0, &set));
  });
  on_a_thread([] {
    const std::string why = make_thread_realtime("publish", 0, CPU_SETSIZE - 1);  // no such CPU here
    EXPECT_NE(why.find("the publish thread runs on any CPU"), std::string::npos) << why;
  });
}

TEST(Realtime, MemoryLockedExactlyWhenItSaysSo) {
  // The sanitizers' runtime replaces mlockall with a no-op that reports success.
  if (rsd::test::kSanitized) GTEST_SKIP() << "under a sanitizer mlockall locks nothing: nothing to check";
  const std::string why = lock_memory();
  if (why.empty()) {
    EXPECT_GT(locked_kb(), 0);
    munlockall();
  } else {
    EXPECT_NE(why.find("memory stays pageable"), std::string::npos) << why;
    EXPECT_EQ(locked_kb(), 0);
  }
}
