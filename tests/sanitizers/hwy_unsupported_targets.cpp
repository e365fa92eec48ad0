// Prints "UNSUPPORTED;SSE4": the Highway targets this file is compiled for that the machine it
// runs on cannot run (a bit mask, decimal), the static target excepted, and 1 if the machine
// runs Highway's SSE4 target, else 0. The ASan+UBSan tree compiles its kernels without the
// former (their code could not be tested there) and, where it can, for SSE4 in place of the
// portable static target (CMakeLists.txt).
#include <hwy/targets.h>

#include <cstdio>

int main() {
  const long long supported = hwy::SupportedTargets();
  const long long unsupported = HWY_ATTAINABLE_TARGETS & ~supported & ~HWY_STATIC_TARGET;
  std::printf("%lld;%d", unsupported, (supported & HWY_SSE4) != 0 ? 1 : 0);
}
