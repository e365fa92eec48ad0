// The rectify stage's worker pool (daemon/worker_pool): every part runs exactly once per job,
// the helpers really run at the same time as the caller, a job allocates nothing, jobs follow
// one another without losing or repeating parts (also jobs of different sizes, where a late
// helper could claim a stale part), and a bad worker count is refused.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <mutex>
#include <thread>
#include <vector>

#include "daemon/worker_pool.hpp"
#include "tests/support/allocation_counter.hpp"  // every C++ allocation of this process, counted

using rsd::daemon::WorkerPool;

namespace {

struct Tally {
  std::vector<std::atomic<int>> runs;
  explicit Tally(int parts) : runs(parts) {}
  static void part(void* ctx, int p) { static_cast<Tally*>(ctx)->runs[p].fetch_add(1); }
};

// Aborts the test binary, naming `what`, unless disarmed (destroyed) within `limit`: a run()
// that never returns (a part lost or run twice, so the count it waits for is never seen) fails
// within a minute, not at the test driver's timeout.
class Watchdog {
 public:
  Watchdog(const char* what, std::chrono::seconds limit) : thread_([this, what, limit] {
    std::unique_lock<std::mutex> lock(mutex_);
    if (!done_cv_.wait_for(lock, limit, [this] { return done_; })) {
      std::fprintf(stderr, "%s: still running after %lld s (a part was lost or repeated)\n", what,
                   static_cast<long long>(limit.count()));
      std::abort();
    }
  }) {}
  ~Watchdog() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    done_cv_.notify_one();
    thread_.join();
  }

 private:
  std::mutex mutex_;
  std::condition_variable done_cv_;
  bool done_ = false;
  std::thread thread_;
};

// Every test of this binary, in well under a second when the pool is right.
const Watchdog kWatchdog("test_worker_pool", std::chrono::seconds(60));

}  // namespace

TEST(WorkerPool, EveryPartRunsExactlyOncePerJob) {
  for (int workers : {1, 2, 3, 5})
    for (int parts : {1, 2, 3, 7, 16}) {
      WorkerPool pool(workers);
      EXPECT_EQ(pool.concurrency(), workers);
      Tally tally(parts);
      for (int job = 0; job < 200; ++job) pool.run(parts, Tally::part, &tally);
      for (int p = 0; p < parts; ++p)
        ASSERT_EQ(tally.runs[p].load(), 200) << workers << " workers, " << parts << " parts, part " << p;
    }
}

// Jobs of different sizes back to back, each with its own tally: a helper that wakes late for
// one job must neither run a part of it after run() returned nor a part beyond the next job's
// count (a claim checks the job and its part count in one atomic ticket).
TEST(WorkerPool, JobsOfDifferentSizesNeverShareAPart) {
  constexpr int kSizes[] = {16, 1, 7, 2, 3, 16, 1};
  for (int workers : {2, 3, 5}) {
    WorkerPool pool(workers);
    for (int round = 0; round < 300; ++round) {
      const int parts = kSizes[round % 7];
      Tally tally(parts);
      pool.run(parts, Tally::part, &tally);
      for (int p = 0; p < parts; ++p)
        ASSERT_EQ(tally.runs[p].load(), 1) << workers << " workers, job " << round << ", part " << p;
    }
  }
}

TEST(WorkerPool, HelpersRunAtTheSameTimeAsTheCaller) {
  // Two parts that each wait for the other to have started: only two threads at once finish;
  // one thread alone would wait out the deadline (then the test fails, it does not hang).
  WorkerPool pool(2);
  struct Meet {
    std::atomic<int> arrived{0};
    std::atomic<int> met{0};
  } meet;
  pool.run(2, [](void* ctx, int) {
    auto* m = static_cast<Meet*>(ctx);
    m->arrived.fetch_add(1);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (m->arrived.load() < 2 && std::chrono::steady_clock::now() < deadline) std::this_thread::yield();
    if (m->arrived.load() == 2) m->met.fetch_add(1);
  }, &meet);
  EXPECT_EQ(meet.met.load(), 2);
}

TEST(WorkerPool, AJobAllocatesNothing) {
  WorkerPool pool(3);
  Tally tally(6);
  for (int i = 0; i < 10; ++i) pool.run(6, Tally::part, &tally);  // warm-up
  const uint64_t before = g_allocations.load();
  for (int i = 0; i < 2000; ++i) pool.run(6, Tally::part, &tally);
  EXPECT_EQ(g_allocations.load() - before, 0u);
  EXPECT_EQ(tally.runs[5].load(), 2010);
}

TEST(WorkerPool, RefusesAWorkerCountOutOfRange) {
  EXPECT_THROW(WorkerPool(0), std::invalid_argument);
  EXPECT_THROW(WorkerPool(WorkerPool::kMaxWorkers + 1), std::invalid_argument);
}
