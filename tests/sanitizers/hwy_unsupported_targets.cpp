// Prints the Highway targets this file is compiled for that the machine it runs on cannot run
// (a bit mask, decimal), the static target excepted. The ASan+UBSan tree compiles its kernels
// without them (CMakeLists.txt): their code could not be tested there.
#include <hwy/targets.h>

#include <cstdio>

int main() {
  const long long unsupported = HWY_ATTAINABLE_TARGETS & ~hwy::SupportedTargets() & ~HWY_STATIC_TARGET;
  std::printf("%lld", unsupported);
}
