// Counts every C++ heap allocation of the process (plain, array, aligned and nothrow operator new) but
// those of named background threads (below).
// Include from exactly one translation unit of a test or benchmark executable: it replaces the
// global allocation functions. LCM's C transport copies messages with malloc, outside the
// daemon's control, and is not counted.
#pragma once

#include <pthread.h>

#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>

inline std::atomic<uint64_t> g_allocations{0};

namespace rsd::test {
// Background threads that are not the hot path (the online calibration's estimator, named
// "rsd-online" before it allocates) are left out: they may allocate; the hot path may not.
inline bool background_thread() {
  static thread_local const bool background = [] {
    char name[16] = {};
    pthread_getname_np(pthread_self(), name, sizeof name);
    return std::strcmp(name, "rsd-online") == 0;
  }();
  return background;
}

inline void* counted_nothrow(std::size_t n, std::size_t align = 0) noexcept {
  if (!background_thread()) g_allocations.fetch_add(1, std::memory_order_relaxed);
  return align ? std::aligned_alloc(align, (n + align - 1) / align * align) : std::malloc(n ? n : 1);
}

inline void* counted(std::size_t n, std::size_t align = 0) {
  void* p = counted_nothrow(n, align);
  if (!p) throw std::bad_alloc();
  return p;
}
}  // namespace rsd::test

void* operator new(std::size_t n) { return rsd::test::counted(n); }
void* operator new[](std::size_t n) { return rsd::test::counted(n); }
void* operator new(std::size_t n, std::align_val_t a) { return rsd::test::counted(n, static_cast<std::size_t>(a)); }
void* operator new[](std::size_t n, std::align_val_t a) { return rsd::test::counted(n, static_cast<std::size_t>(a)); }
// The nothrow forms too (std::stable_sort's temporary buffer takes one): had they stayed the
// runtime's, their blocks would come back through the free() below, which AddressSanitizer reports
// as an alloc-dealloc mismatch.
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return rsd::test::counted_nothrow(n); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return rsd::test::counted_nothrow(n); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return rsd::test::counted_nothrow(n, static_cast<std::size_t>(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return rsd::test::counted_nothrow(n, static_cast<std::size_t>(a));
}
// These operators replace the global ones, so free() is the right partner of counted()'s malloc;
// GCC, seeing operator delete call free, warns of a mismatch at -O1 (the sanitizer trees).
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
#endif
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
#if defined(__GNUC__) && !defined(__clang__)
#pragma GCC diagnostic pop
#endif
