// The rectify stage's helpers: a fixed team of threads, created at start-up, that resample
// bands of a frame's rows together with the rectify thread (dsp::RowExecutor).
//
// Thread contract: constructed and destroyed by the service thread (start-up, shutdown). run()
// is called by one thread at a time (the rectify thread), which works on the parts itself and
// returns when every part is done and every helper has let go of the job; it allocates nothing
// and waits for nothing but its own parts. Helpers sleep (futex, std::atomic::wait) between
// frames. workers = 1: no helper thread, run() does everything on the caller.
#pragma once

#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include "dsp/rectify/rs_rectifier.hpp"

namespace rsd::daemon {

class WorkerPool final : public dsp::RowExecutor {
 public:
  static constexpr int kMaxWorkers = 64;
  // workers: threads that share a frame, the caller included (1..kMaxWorkers).
  explicit WorkerPool(int workers);
  ~WorkerPool() override;
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  int concurrency() const override { return workers_; }
  void run(int parts, void (*fn)(void* ctx, int part), void* ctx) override;

 private:
  void helper_loop();
  void work();  // takes parts until none is left

  const int workers_;
  std::vector<std::thread> helpers_;
  // The job: written by run() only while no helper is inside it (pending_ == 0).
  void (*fn_)(void*, int) = nullptr;
  void* ctx_ = nullptr;
  int parts_ = 0;
  std::atomic<int> next_{0};                // the next part to hand out
  std::atomic<int> pending_{0};             // helpers still inside the current job
  std::atomic<std::uint32_t> generation_{0};  // bumped per job (and to stop)
  std::atomic<bool> stop_{false};
};

}  // namespace rsd::daemon
