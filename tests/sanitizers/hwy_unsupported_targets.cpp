// Prints "UNSUPPORTED;SSE4": the Highway targets this file is compiled for that the machine it
// runs on cannot run (a bit mask, decimal), the static target excepted, and 1 if the machine
// runs Highway's SSE4 target, else 0. The ASan+UBSan tree compiles its kernels without the
// former (their code could not be tested there) and, where it can, for SSE4 in place of the
// portable static target (CMakeLists.txt).
#include <hwy/targets.h>

#include <cstdio>

#if defined(__x86_64__) || defined(__i386__)
#include <cpuid.h>
#endif

namespace {

// Highway 1.0's AVX3_DL target is compiled with AVX-VNNI ("avxvnni" in its target string) but
// chosen at run time without asking for it: it is not an AVX-512 feature. Clang then encodes the
// 128-bit dot products (vpdpwssd) in AVX-VNNI's VEX form, which a machine with AVX-512 VNNI and
// without AVX-VNNI (Ice Lake, Cascade Lake servers) cannot run: the ASan+UBSan tree's AVX3_DL
// rectifier tests died of SIGILL on such a Xeon (GCC's normal tree runs them there).
bool runs_avx_vnni() {
#if defined(__x86_64__) || defined(__i386__)
  unsigned a = 0, b = 0, c = 0, d = 0;
  return __get_cpuid_count(7, 1, &a, &b, &c, &d) && ((a >> 4) & 1u) != 0;  // CPUID.(7,1):EAX[4]
#else
  return true;
#endif
}

}  // namespace

int main() {
  const long long supported = hwy::SupportedTargets();
  long long unsupported = HWY_ATTAINABLE_TARGETS & ~supported & ~HWY_STATIC_TARGET;
  if (!runs_avx_vnni()) unsupported |= HWY_ATTAINABLE_TARGETS & HWY_AVX3_DL & ~HWY_STATIC_TARGET;
  std::printf("%lld;%d", unsupported, (supported & HWY_SSE4) != 0 ? 1 : 0);
}
