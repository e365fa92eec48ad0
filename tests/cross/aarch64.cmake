# CMake toolchain for arm64 (Raspberry Pi 4/5, Jetson): Debian's cross compiler, the arm64
# libraries Debian installs beside the native ones (multiarch, /usr/lib/aarch64-linux-gnu), and
# qemu-user-static to run what it builds (tests/cross/run.sh; docs/performance.md, "ARM").
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)
set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

# Programs from the build machine; libraries and headers of the target only (the cross
# compiler's own tree and the multiarch directory).
set(CMAKE_FIND_ROOT_PATH /usr/aarch64-linux-gnu)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)

# ctest (and gtest_discover_tests at build time) run the arm64 binaries through qemu: the
# loader and libc from the cross tree, the multiarch libraries (Highway) beside them.
# RSD_TEST_NO_THREADS: Debian 12's qemu-user (7.2) hangs in pthread_create on this machine's
# kernel, so tests that start threads of their own run their single-threaded part only there.
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64-static -L /usr/aarch64-linux-gnu
    -E LD_LIBRARY_PATH=/usr/lib/aarch64-linux-gnu -E RSD_TEST_NO_THREADS=qemu-user)
