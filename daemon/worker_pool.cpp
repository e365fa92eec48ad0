#include "daemon/worker_pool.hpp"

#include <sched.h>

#include <chrono>
#include <stdexcept>
#include <string>

namespace rsd::daemon {

namespace {

// How long a helper keeps polling for the next job before it sleeps: longer than the gaps
// between a frame's jobs (the serial parts of the map), far shorter than a frame period.
constexpr auto kSpin = std::chrono::microseconds(50);

// Polling only pays where every thread of the team has a CPU of its own: otherwise a polling
// helper would take the CPU from the thread that works.
bool cpus_for(int threads) {
  cpu_set_t set;
  CPU_ZERO(&set);
  return sched_getaffinity(0, sizeof set, &set) == 0 && CPU_COUNT(&set) >= threads;
}

void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#elif defined(__aarch64__)
  asm volatile("yield" ::: "memory");
#endif
}

constexpr std::uint64_t make_ticket(std::uint32_t generation, int parts) {
  return std::uint64_t{generation} << 32 | static_cast<std::uint64_t>(parts) << 16;
}

}  // namespace

WorkerPool::WorkerPool(int workers) : workers_(workers) {
  if (workers < 1 || workers > kMaxWorkers)
    throw std::invalid_argument("rectification.workers must be 1.." + std::to_string(kMaxWorkers));
  spin_ = cpus_for(workers) ? kSpin : std::chrono::microseconds(0);
  helpers_.reserve(workers - 1);
  for (int i = 1; i < workers; ++i) helpers_.emplace_back([this] { helper_loop(); });
}

WorkerPool::~WorkerPool() {
  stop_.store(true, std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  for (std::thread& t : helpers_) t.join();
}

// One part of the current job, if any is left. The acquire pairs with run()'s release of the
// ticket: a claimed part's job (fn_, ctx_) is visible, and stays unchanged until the part is done.
bool WorkerPool::claim(int& part, int& parts) {
  std::uint64_t t = ticket_.load(std::memory_order_acquire);
  for (;;) {
    parts = static_cast<int>(t >> 16 & 0xFFFF);
    const int next = static_cast<int>(t & 0xFFFF);
    if (next >= parts) return false;
    if (ticket_.compare_exchange_weak(t, t + 1, std::memory_order_acquire, std::memory_order_acquire)) {
      part = next;
      return true;
    }
  }
}

void WorkerPool::work() {
  for (int part = 0, parts = 0; claim(part, parts);) {
    fn_(ctx_, part);
    if (done_.fetch_add(1, std::memory_order_acq_rel) + 1 == parts) done_.notify_one();
  }
}

void WorkerPool::run(int parts, void (*fn)(void*, int), void* ctx) {
  if (parts > kMaxParts) throw std::invalid_argument("WorkerPool::run: more than 65535 parts");
  if (helpers_.empty()) {
    for (int p = 0; p < parts; ++p) fn(ctx, p);
    return;
  }
  if (parts < 1) return;
  // No part of the previous job is claimable or running: the job may be rewritten.
  fn_ = fn, ctx_ = ctx;
  done_.store(0, std::memory_order_relaxed);
  const std::uint32_t generation = generation_.load(std::memory_order_relaxed) + 1;
  ticket_.store(make_ticket(generation, parts), std::memory_order_release);  // publishes the job
  generation_.store(generation, std::memory_order_release);
  generation_.notify_all();
  work();
  // The parts the helpers claimed: running now, each a share of the frame's work.
  for (int n = done_.load(std::memory_order_acquire), spins = 0; n != parts; n = done_.load(std::memory_order_acquire))
    if (++spins < 4096)
      cpu_relax();
    else
      done_.wait(n, std::memory_order_acquire);
}

// Until the generation moves on from `seen`: polling for spin_, then asleep.
void WorkerPool::await_job(std::uint32_t seen) {
  const auto until = std::chrono::steady_clock::now() + spin_;
  for (int i = 1; generation_.load(std::memory_order_acquire) == seen; ++i) {
    if (i % 64 == 0 && std::chrono::steady_clock::now() > until) {
      generation_.wait(seen, std::memory_order_acquire);
      return;
    }
    cpu_relax();
  }
}

void WorkerPool::helper_loop() {
  std::uint32_t seen = 0;  // the constructor's generation
  for (;;) {
    await_job(seen);
    seen = generation_.load(std::memory_order_acquire);
    if (stop_.load(std::memory_order_relaxed)) return;
    work();
  }
}

}  // namespace rsd::daemon
