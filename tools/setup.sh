#!/usr/bin/env bash
# Installs every Debian package rsd needs to build, run and test.
# Non-interactive and idempotent: safe to run again; it is the only set-up step.
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git  # Ninja: the README builds with it (finer-grained parallel steps than make)
  lld                      # the linker every tree uses (CMakeLists.txt: four times GNU ld's speed)
  libeigen3-dev            # linear algebra (dsp/)
  libboost-dev             # Boost.Math bracketed root finding (dsp/)
  libgtest-dev libgmock-dev # unit tests
  libbenchmark-dev         # benchmarks
  libcli11-dev             # command-line parsing (tools/)
  libspdlog-dev            # logging
  libplplot-dev plplot-driver-cairo  # plots (PNG/SVG) from the tools
  libceres-dev             # least squares: bundle adjustment, diagnosis fits
  liblapack-dev            # band Cholesky of the diagnosis's translation spline (dsp/diagnosis)
  libyaml-cpp-dev          # scenario, recording and config files
  libfftw3-dev             # FFT for LED-flicker row-rate calibration
  libpng-dev               # PNG frames in and out
  liblcm-dev liblcm-bin liblcm-java libglib2.0-dev  # LCM messages, lcm-gen, lcm-logger, lcm-spy
  default-jdk-headless libjchart2d-java  # Java LCM types for lcm-spy
  libopencv-dev libopencv-contrib-dev    # AprilTag codes (aruco), feature tracking, reference remap
  libavformat-dev                        # GoPro MP4s: the GPMF gyro track (formats/gpmf_mp4)
  libsystemd-dev systemd python3         # sd_notify; unit verification and notify tests
  help2man dpkg-dev procps               # man pages from --help; the Debian package (cpack, dpkg-shlibdeps); kill
  libcamera-dev                          # the libcamera driver
  libaravis-dev aravis-tools libusb-1.0-0-dev iproute2 util-linux  # Aravis driver; fake GigE camera tests in a private netns
  clang libfuzzer-14-dev                 # fuzzing the parsers (tests/fuzz/run.sh)
  libhwy-dev                             # Google Highway: the SIMD kernels (dsp/rectify)
)
# On x86-64: the arm64 cross build and its tests under qemu (tests/cross), with Highway for arm64
# from Debian's multiarch archive beside the native one. An arm64 machine tests its own kernels.
if [ "$(dpkg --print-architecture)" = amd64 ]; then
  PACKAGES+=(g++-aarch64-linux-gnu qemu-user-static libhwy-dev:arm64)
fi

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PACKAGES[@]} packages already installed"
  exit 0
fi

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
# arm64 packages on x86-64 (multiarch) need the architecture known to dpkg before apt-get update.
if [ "$(dpkg --print-architecture)" = amd64 ] && ! dpkg --print-foreign-architectures | grep -qx arm64; then
  $SUDO dpkg --add-architecture arm64
fi
$SUDO apt-get update -q
$SUDO apt-get install -y -q --no-install-recommends "${missing[@]}"
