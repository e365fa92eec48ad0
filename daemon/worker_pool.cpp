#include "daemon/worker_pool.hpp"

#include <stdexcept>
#include <string>

namespace rsd::daemon {

WorkerPool::WorkerPool(int workers) : workers_(workers) {
  if (workers < 1 || workers > kMaxWorkers)
    throw std::invalid_argument("rectification.workers must be 1.." + std::to_string(kMaxWorkers));
  helpers_.reserve(workers - 1);
  for (int i = 1; i < workers; ++i) helpers_.emplace_back([this] { helper_loop(); });
}

WorkerPool::~WorkerPool() {
  stop_.store(true, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  for (std::thread& t : helpers_) t.join();
}

void WorkerPool::work() {
  for (int p = next_.fetch_add(1, std::memory_order_relaxed); p < parts_;
       p = next_.fetch_add(1, std::memory_order_relaxed))
    fn_(ctx_, p);
}

void WorkerPool::run(int parts, void (*fn)(void*, int), void* ctx) {
  if (helpers_.empty()) {
    for (int p = 0; p < parts; ++p) fn(ctx, p);
    return;
  }
  fn_ = fn, ctx_ = ctx, parts_ = parts;
  next_.store(0, std::memory_order_relaxed);
  pending_.store(static_cast<int>(helpers_.size()), std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);  // publishes the job
  generation_.notify_all();
  work();
  // Every helper checks out of the job after its last part: then all parts are done, their
  // pixels are visible here (acquire), and the next job may overwrite fn_, ctx_, parts_.
  for (int n = pending_.load(std::memory_order_acquire); n != 0; n = pending_.load(std::memory_order_acquire))
    pending_.wait(n, std::memory_order_acquire);
}

void WorkerPool::helper_loop() {
  std::uint32_t seen = 0;  // the constructor's generation
  for (;;) {
    generation_.wait(seen, std::memory_order_acquire);
    seen = generation_.load(std::memory_order_acquire);
    if (stop_.load(std::memory_order_relaxed)) return;
    work();
    if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) pending_.notify_one();
  }
}

}  // namespace rsd::daemon
