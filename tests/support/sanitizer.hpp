// Whether this test binary runs under a sanitizer (tests/sanitizers/run.sh builds such trees) or
// an emulator (the arm64 cross build under qemu-user, tests/cross), so that a test with a time
// limit can widen it, or a long numerical test check fewer points or skip itself, saying so.
// AddressSanitizer costs about 2x, ThreadSanitizer 5-15x, qemu 10-30x; limits that hold on a
// loaded two-core machine at full speed do not hold there, while what the test checks (order,
// counts, values) still must.
#pragma once

namespace rsd::test {

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

// Built for another machine and run under qemu-user (tests/cross/dsp_only.cmake defines it).
#ifdef RSD_TEST_EMULATED
inline constexpr bool kEmulated = true;
#else
inline constexpr bool kEmulated = false;
#endif

// Either: every instruction costs several times what it does at full speed.
inline constexpr bool kSlowBuild = kSanitized || kEmulated;

// How much longer a timed step may take under a sanitizer than at full speed.
inline constexpr double kTimeScale = kSanitized ? 10.0 : 1.0;

inline constexpr const char* kSanitizedNote = "under a sanitizer: time limits widened tenfold";

}  // namespace rsd::test

// A test whose arithmetic alone takes tens of seconds at full speed (a diagnosis over a whole
// recording) would take ten to thirty times that under AddressSanitizer or qemu, beyond any
// budget: it skips itself there, naming the faster tests that run the same code there (as
// Suite.Test or Suite.*; the CTest skip_messages_name_tests_that_run checks that each exists and
// does not skip itself too). Its numbers are checked in the normal tree.
#define RSD_SKIP_LONG_IN_SLOW_BUILD(covered_by)                                                             \
  do {                                                                                                      \
    if (::rsd::test::kSlowBuild)                                                                            \
      GTEST_SKIP() << "a long numerical run, skipped under a sanitizer or an emulator; its code runs there in " \
                   << covered_by;                                                                           \
  } while (0)
