// The ranges numbers from outside must lie in, in one place. The boundary where a number enters
// (configuration, calibration and intrinsics files, recordings, logs, network frames, camera
// metadata) checks it against these before anything is computed from it, and they are what the
// later stages can use: a size the rectifier refuses is refused where it enters too, so that
// `rsd --check-config` and a SIGHUP refuse exactly what would fail later, and a running daemon
// never meets a value it cannot handle. docs/reliability.md has the table.
#pragma once

#include <cmath>
#include <cstdint>

namespace rsd::dsp::limits {

// A closed range of finite numbers and its text for error messages.
struct Range {
  double lo, hi;
  const char* text;
  constexpr bool contains(double v) const { return v >= lo && v <= hi; }  // NaN and infinities: no
};

// Times from outside (frame stamps, log event times, motion stamps), in nanoseconds: within
// +-2^61 ns, 73 years either side of the clock's epoch (every CLOCK_MONOTONIC and Unix time of a
// real system). They enter as dsp::Stamp (dsp/core/stamp.hpp), which checks this window once and
// never overflows when combined.
inline constexpr int64_t kStampLimitNs = int64_t{1} << 61;

// Frame sides: the rectifier's maps (4 px and up; its 16.16 fixed-point positions reach
// +-16384 px, which 8000 px and the margins around them stay within).
inline constexpr int kMinSide = 4, kMaxSide = 8000;
inline constexpr Range kSide{kMinSide, kMaxSide, "4..8000 pixels"};
inline constexpr bool side_ok(double v) { return kSide.contains(v) && v == std::floor(v); }

// Frame rates: 1/fps periods and readouts must stay finite and the frame loop must advance.
inline constexpr Range kFrameRateHz{1e-3, 1e5, "0.001..100000 Hz"};
// A motion sensor's sample rate (the simulator's IMU; a faster one would spin, not sample).
inline constexpr Range kMotionRateHz{0.1, 1e4, "0.1..10000 Hz"};
inline constexpr Range kLineDelayS{0, 1, "0..1 s"};
inline constexpr Range kExposureS{0, 10, "0..10 s"};
// Focal lengths in pixels: below 1 px or above 10^7 px no camera images (and the projections'
// arithmetic loses every digit, leaving a black frame labelled rectified).
inline constexpr Range kFocalPx{1, 1e7, "1..1e7 pixels"};
// The principal point, in image widths or heights from the image's corner: within the image
// give or take a few sizes (a cropped or shifted sensor), never far away.
inline constexpr Range kPrincipalPointSizes{-4, 5, "-4..5 image sizes"};
// Lens distortion coefficients (Brown-Conrady k1 k2 p1 p2 k3, equidistant k1..k4).
inline constexpr Range kDistortion{-1e3, 1e3, "-1000..1000"};
// Clock offsets between a motion sensor and the camera (time_offset_s, Kalibr's
// timeshift_cam_imu): a day either way. Beyond, microsecond arithmetic on stamps overflows.
inline constexpr Range kTimeShiftS{-86400, 86400, "-86400..86400 s"};
// A motion sensor's clock drift against the camera's, its gyro's scale and bias, its offset
// from the camera's centre.
inline constexpr Range kDriftPpm{-1e4, 1e4, "-10000..10000 ppm"};
inline constexpr Range kGyroScale{0.1, 10, "0.1..10"};
inline constexpr Range kGyroBiasRadS{-10, 10, "-10..10 rad/s"};
inline constexpr Range kLeverArmM{-100, 100, "-100..100 m"};

}  // namespace rsd::dsp::limits
