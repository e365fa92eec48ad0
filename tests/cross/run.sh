#!/bin/sh
# The arm64 cross build and its tests: dsp's geometry and rectification (RSD_DSP_ONLY) built
# with Debian's aarch64 cross compiler (tests/cross/aarch64.cmake) and their tests run under
# qemu-user-static, so that Highway's NEON, SVE and SVE2 kernels are checked against the
# scalar reference on this x86-64 machine. CTest `cross_aarch64` runs it (tests/cross).
#   run.sh SRC BUILD
set -eu
src=$1 build=$2
mkdir -p "$build"
jobs=$(nproc)
# Ninja where the machine has it, as the other trees (tools/setup.sh installs it); a tree keeps
# the generator it was first configured with.
generator=""
[ -f "$build/CMakeCache.txt" ] || ! command -v ninja >/dev/null 2>&1 || generator="-G Ninja"
# shellcheck disable=SC2086  # the generator is two words or none
cmake -S "$src" -B "$build" $generator -DCMAKE_TOOLCHAIN_FILE="$src/tests/cross/aarch64.cmake" -DRSD_DSP_ONLY=ON \
      -DCMAKE_BUILD_TYPE=Release >"$build/configure.log" 2>&1 || { cat "$build/configure.log"; exit 1; }
cmake --build "$build" -j"$jobs"
ctest --test-dir "$build" -j"$jobs" --output-on-failure
