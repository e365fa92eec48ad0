// The rectify stage's helpers: a fixed team of threads, created at start-up, that solve map
// columns and resample bands of a frame's rows together with the rectify thread
// (dsp::RowExecutor).
//
// Thread contract: constructed and destroyed by the service thread (start-up, shutdown). run()
// is called by one thread at a time (the rectify thread), which works on the parts itself and
// returns when every part is done; it allocates nothing and waits for nothing but parts that
// are running: a helper that wakes late finds the job's parts taken and does nothing, and the
// caller does not wait for it. Parts are claimed through one atomic ticket (job, parts, next
// part), so a stale helper can never claim a part of a finished job. After a job a helper polls
// for up to 50 us (a frame's jobs follow one another within microseconds: the map's columns, then
// the rows) when the process has a CPU for every thread, and then sleeps (futex,
// std::atomic::wait) until the next frame. workers = 1: no helper thread, run() does everything
// on the caller.
#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>
#include <vector>

#include "dsp/rectify/rs_rectifier.hpp"

namespace rsd::daemon {

class WorkerPool final : public dsp::RowExecutor {
 public:
  static constexpr int kMaxWorkers = 64;
  static constexpr int kMaxParts = 0xFFFF;  // parts of one job
  // workers: threads that share a frame, the caller included (1..kMaxWorkers).
  explicit WorkerPool(int workers);
  ~WorkerPool() override;
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int concurrency() const override { return workers_; }
  void run(int parts, void (*fn)(void* ctx, int part), void* ctx) override;

 private:
  void helper_loop();
  void await_job(std::uint32_t seen);
  bool claim(int& part, int& parts);
  void work();  // claims parts and runs them until none is left

  const int workers_;
  std::vector<std::thread> helpers_;
  // The job: written by run() only while no part of the previous one can be claimed or running.
  void (*fn_)(void*, int) = nullptr;
  void* ctx_ = nullptr;
  // generation << 32 | parts << 16 | next part: a claim is one compare-exchange on all three.
  std::atomic<std::uint64_t> ticket_{0};
  std::atomic<int> done_{0};                  // parts of the current job finished
  std::atomic<std::uint32_t> generation_{0};  // bumped per job (and to stop): what sleepers wait on
  std::atomic<bool> stop_{false};
  std::chrono::microseconds spin_{0};         // how long a helper polls after a job (cpus_for)
};

}  // namespace rsd::daemon
