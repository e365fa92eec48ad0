// Line-delay calibration with a blinking LED (Meingast, Geyer, Sastry 2005, Sec.
// "Calibration" and its table).
//
// A lens-less sensor facing an LED blinking at a known frequency f sees horizontal bars:
// row y of frame k is exposed at t_k + delta y (eq. (1) with r = 1/delta), so the light
// it records is periodic in y with spatial frequency nu = f delta cycles/row. The paper
// sums a subset of columns of every frame into the spatio-temporal image I(y, t), takes
// its 2-D Fourier transform, marginalises it over temporal frequency and reads r off the
// highest peak. Its table reports delta to +-0.0005 s; this module aims at 1% or better:
//
//   1. Column blocks are reduced to row profiles as frames arrive (any frame source can
//      push frames; nothing but the profiles is kept).
//   2. The profiles are summed with weights given by each block's modulation, so dark,
//      saturated or unlit columns do not dilute the signal; the 2x2 Bayer pattern's
//      alternating row gains are removed by normalising the row parity.
//   3. Seed: the paper's marginalised 2-D spectrum (fundamental, not a harmonic, of a
//      square-wave drive), or, when frame times are known and the pattern moves between
//      frames, the 2-D Fourier transform taken at the LED's own temporal frequency.
//   4. A joint nonlinear least-squares sinusoid fit (Ceres) over all rows and frames:
//        I(k, y) = a(y) + b(y) cos(2 pi f (t_k + delta y) + phi)
//      with a per-row offset and gain a, b (uneven illumination, gamma, clipping all
//      become per-row nuisances) when frame times t_k are known; with smooth a, b
//      (cubic B-splines) when the pattern is frozen between frames (f near a multiple of
//      the frame rate); or frame by frame, each with its own phase and smooth a, b, when
//      frame times are unknown. The waveform's harmonics (square-wave drive, gamma,
//      clipping) are part of the model.
//   5. Uncertainty: the fit's covariance (classical or cluster-robust, the larger), the
//      waveform's truncation, a 2e-5 relative floor and the LED frequency's accuracy.
//
// estimate() plans FFTs with FFTW, whose planner is not thread-safe: do not run two
// estimates at once in one process.
//
// See docs/led-calibration.md for the method, the reproduced table and the limits.
//
// Sign: nu > 0 for a top-to-bottom readout. Only a fit with known frame times sees the
// sign; the others report |nu|.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "dsp/core/image.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::dsp {

struct LedCalibrationOptions {
  double led_hz = 0;          // the LED (pulse generator) frequency; must be > 0
  std::optional<double> fps;  // frame rate: frame k starts at k / fps (joint model, d verdict)
  int max_frames = 240;       // later frames are ignored (and reported in the warnings)
  double zero_delay_sigmas = 3;  // d counts as zero when |d| <= this many sigma
  double led_hz_accuracy = 0;    // relative accuracy of led_hz (1e-4: 100 ppm); adds to the uncertainty
};

// Which model the final fit used (see the file comment).
enum class LedModel { JointPerRow, JointSmooth, PerFrame };
std::string_view to_string(LedModel m);

struct LedCalibrationResult {
  // Spatial frequency of the bars, the fit's and the paper's (spectral peak) estimates.
  double nu_cycles_per_row = 0, nu_sigma = 0;
  double spectral_peak_cycles_per_row = 0;

  // Timing, each with its 1-sigma uncertainty. line_delay = |nu| / f; its uncertainty
  // includes a 2e-5 relative model floor and LedCalibrationOptions::led_hz_accuracy.
  double line_delay_s = 0, line_delay_sigma_s = 0;
  double row_rate_hz = 0, row_rate_sigma_hz = 0;          // |r| = 1 / line delay
  double frame_readout_s = 0, frame_readout_sigma_s = 0;  // rows * line delay
  // The paper's d = frame period - readout; needs the frame rate (option or timestamps).
  std::optional<double> frame_period_s, blanking_s, blanking_sigma_s;
  std::optional<bool> zero_delay;  // |d| <= zero_delay_sigmas * sigma
  std::optional<Readout> readout;  // when the data show it (joint fit, moving pattern)

  LedModel model = LedModel::PerFrame;
  int frames_used = 0, rows = 0, width = 0, columns_used = 0;
  double cycles_per_frame = 0;   // |nu| * rows
  double modulation_depth = 0;   // median over rows of |b| / a
  double snr = 0;                // fitted amplitude / residual rms, per sample
  std::vector<std::string> warnings;
};

// The capture holds no measurable LED modulation, or too little of it for the model.
struct LedCalibrationError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Accumulates frames (from files, a log or a live camera) and estimates the line delay.
// Frames are reduced to column-block row profiles on arrival; nothing else is kept.
class LedCalibrator {
 public:
  // Throws std::invalid_argument unless led_hz > 0, fps (if given) > 0, max_frames >= 1.
  explicit LedCalibrator(const LedCalibrationOptions& opt);

  // Adds the next frame. Timestamps (seconds, any origin) are used instead of k / fps
  // when every frame has one. Throws std::invalid_argument when the frame's size differs
  // from the first frame's, or it has fewer than 16 rows or 2 columns.
  void add_frame(const ImageView& frame, std::optional<double> timestamp_s = std::nullopt);

  int frames() const { return static_cast<int>(profiles_.size()); }

  // Throws LedCalibrationError when no LED modulation is found or the model cannot
  // separate it from the illumination (too few bars and no frame times).
  LedCalibrationResult estimate() const;

 private:
  LedCalibrationOptions opt_;
  int width_ = 0, height_ = 0, block_width_ = 0, blocks_ = 0, ignored_ = 0;
  PixelFormat format_ = PixelFormat::Mono8;
  std::vector<std::vector<double>> profiles_;  // per frame: blocks_ x height_ column sums
  std::vector<std::optional<double>> times_;
};

// Convenience: all frames at once.
LedCalibrationResult calibrate_led(const std::vector<ImageView>& frames, const LedCalibrationOptions& opt);

}  // namespace rsd::dsp
