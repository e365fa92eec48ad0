// A bounded, lock-free queue of frame-slot indices between two pipeline threads, in which
// the producer never blocks: when the queue is full it takes the oldest entry back itself
// (a dropped frame, whose slot it reuses) instead of waiting for the consumer.
//
// One producer thread calls push()/reclaim_oldest(); one consumer thread calls pop(). Both
// sides take entries from the head with a compare-and-swap, so exactly one of them wins each
// entry; the tail is written by the producer alone. Capacity is fixed at construction; no
// allocation afterwards.
#pragma once

#include <atomic>
#include <cstdint>
#include <optional>
#include <vector>

namespace rsd::daemon {

class DropOldestQueue {
 public:
  explicit DropOldestQueue(size_t capacity) : ring_(capacity), cap_(capacity) {}

  // Producer: appends; returns false if full (then reclaim_oldest() and retry).
  bool push(uint32_t slot) {
    const uint64_t t = tail_.load(std::memory_order_relaxed);
    if (t - head_.load(std::memory_order_acquire) >= cap_) return false;
    ring_[t % cap_].store(slot, std::memory_order_relaxed);
    tail_.store(t + 1, std::memory_order_release);
    wake();
    return true;
  }

  // Consumer: sleeps until something is pushed or wake() is called after `seen`, the value
  // of epoch() read before the queue was found empty. A futex under the hood (C++20 atomic
  // wait): no lock, and a push with nobody waiting costs one atomic increment.
  uint32_t epoch() const { return epoch_.load(std::memory_order_acquire); }
  void wait(uint32_t seen) const { epoch_.wait(seen, std::memory_order_acquire); }
  // Wakes a waiting consumer (after a push, or to let it see that the producer is done).
  void wake() {
    epoch_.fetch_add(1, std::memory_order_release);
    epoch_.notify_all();
  }

  // Consumer: the oldest entry, if any.
  std::optional<uint32_t> pop() { return take(); }

  // Producer: takes the oldest entry back (the frame is dropped), if the consumer has not
  // taken it first.
  std::optional<uint32_t> reclaim_oldest() { return take(); }

  size_t size() const {
    return static_cast<size_t>(tail_.load(std::memory_order_acquire) - head_.load(std::memory_order_acquire));
  }
  size_t capacity() const { return cap_; }

 private:
  std::optional<uint32_t> take() {
    uint64_t h = head_.load(std::memory_order_acquire);
    for (;;) {
      if (h == tail_.load(std::memory_order_acquire)) return std::nullopt;
      // Read before claiming: the producer cannot overwrite position h until head passes it.
      const uint32_t slot = ring_[h % cap_].load(std::memory_order_relaxed);
      if (head_.compare_exchange_weak(h, h + 1, std::memory_order_acq_rel, std::memory_order_acquire)) return slot;
    }
  }

  std::vector<std::atomic<uint32_t>> ring_;
  const size_t cap_;
  alignas(64) std::atomic<uint64_t> head_{0};
  alignas(64) std::atomic<uint64_t> tail_{0};
  alignas(64) std::atomic<uint32_t> epoch_{0};
};

// Slots not in use by anyone, handed back by consumers to the producer of a stage: a plain
// single-producer single-consumer ring (it can never overflow: it holds at most every slot).
class FreeList {
 public:
  explicit FreeList(size_t capacity) : q_(capacity) {}
  void put(uint32_t slot) { (void)q_.push(slot); }
  std::optional<uint32_t> get() { return q_.pop(); }
  size_t size() const { return q_.size(); }

 private:
  DropOldestQueue q_;
};

}  // namespace rsd::daemon
