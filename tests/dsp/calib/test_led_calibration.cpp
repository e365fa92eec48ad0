// LED line-delay calibration (dsp/calib/led_calibration.hpp) against synthetic captures whose
// timing is known exactly (dsp/calib/led_capture_synthesis.hpp): the paper's calibration table
// (Meingast, Geyer, Sastry 2005, Sec. "Calibration") to 1% instead of +-0.0005 s, the
// robustness cases one at a time and combined, a consumer-camera frame, the uncertainty
// against the actual scatter, and the errors.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "dsp/calib/led_calibration.hpp"
#include "dsp/calib/led_capture_synthesis.hpp"

using namespace rsd::dsp;

namespace {

// ---------------------------------------------------------------- helpers

struct Measured {
  LedCalibrationResult r;
  double truth = 0;  // true line delay (s)
  double err() const { return r.line_delay_s / truth - 1; }
  double sigma() const { return r.line_delay_sigma_s / truth; }
};

LedCalibrationResult estimate(const LedCapture& cap, const LedCalibrationOptions& o, bool stamps = false) {
  LedCalibrator cal(o);
  for (size_t k = 0; k < cap.frames.size(); ++k) {
    Image frame = cap.frames[k];  // views need mutable data
    cal.add_frame(frame.view(), stamps ? std::optional<double>(cap.times_s[k]) : std::nullopt);
  }
  return cal.estimate();
}

Measured calibrate(const LedCaptureSpec& s, bool with_fps = true, bool stamps = false) {
  LedCalibrationOptions o;
  o.led_hz = s.led_hz;
  if (with_fps) o.fps = s.fps;
  return {estimate(synthesize_led_capture(s), o, stamps), s.line_delay_s()};
}

bool has_warning(const LedCalibrationResult& r, const std::string& text) {
  return std::any_of(r.warnings.begin(), r.warnings.end(),
                     [&](const std::string& w) { return w.find(text) != std::string::npos; });
}

// The paper's set-up: 240 rows read per frame, a square-wave LED, 5 ms exposure, some
// vignetting and noise, 8-bit frames.
LedCaptureSpec paper_capture(double fps, double led_hz) {
  LedCaptureSpec s;
  s.width = 160;
  s.height = 240;
  s.frames = 12;
  s.fps = fps;
  s.led_hz = led_hz;
  s.exposure_s = 0.005;
  s.vignetting = 0.3;
  s.noise = 2;
  return s;
}

// The accuracy claim: within 1% of the truth, and the error consistent with the reported
// 1-sigma uncertainty, which itself is informative (below 1%).
void expect_accurate(const Measured& run, const std::string& what) {
  SCOPED_TRACE(what);
  EXPECT_LT(std::abs(run.err()), 0.01) << "line delay " << run.r.line_delay_s << " s, truth " << run.truth;
  EXPECT_LE(std::abs(run.err()), 3 * run.sigma()) << "error " << run.err() << ", sigma " << run.sigma();
  EXPECT_LT(run.sigma(), 0.01);
}

// ---------------------------------------------------------------- the generator's ground truth

TEST(LedSynthesis, MeanBrightnessIsTheWaveformsAverage) {
  LedCaptureSpec s;
  s.led_hz = 10;
  s.duty = 0.3;
  s.led_phase_cycles = 0;
  EXPECT_DOUBLE_EQ(led_mean_brightness(s, 0.01, 0), 1.0);   // 0.1 cycle: on
  EXPECT_DOUBLE_EQ(led_mean_brightness(s, 0.05, 0), 0.0);   // 0.5 cycle: off
  EXPECT_NEAR(led_mean_brightness(s, 0.123, 0.1), 0.3, 1e-12);   // one period: the duty
  EXPECT_NEAR(led_mean_brightness(s, 0.0, 0.03), 1.0, 1e-12);    // within the on-time
  EXPECT_NEAR(led_mean_brightness(s, 0.02, 0.02), 0.5, 1e-12);   // half on, half off
  s.waveform = LedWaveform::Sine;
  EXPECT_NEAR(led_mean_brightness(s, 0.0, 0), 1.0, 1e-12);
  EXPECT_NEAR(led_mean_brightness(s, 0.05, 0), 0.0, 1e-12);
  EXPECT_NEAR(led_mean_brightness(s, 0.07, 0.2), 0.5, 1e-12);    // two periods
}

// Independent of the estimator: in a clean capture the bars' edges are half an LED period
// apart in time, i.e. 1 / (2 f line_delay) rows apart.
TEST(LedSynthesis, BarEdgesAreHalfAnLedPeriodApart) {
  LedCaptureSpec s;
  s.width = 8;
  s.frames = 1;
  s.fps = 15;
  s.led_hz = 103;
  const Image img = synthesize_led_capture(s).frames[0];
  std::vector<int> edges;
  for (int y = 1; y < s.height; ++y)
    if ((img.data[y * s.width] > 100) != (img.data[(y - 1) * s.width] > 100)) edges.push_back(y);
  ASSERT_GE(edges.size(), 10u);
  const double spacing = double(edges.back() - edges.front()) / (edges.size() - 1);
  EXPECT_NEAR(spacing, 1 / (2 * s.led_hz * s.line_delay_s()), 0.1);  // 17.48 rows
}

// ---------------------------------------------------------------- the paper's table

struct TableCase {
  double fps, led_hz;
};

class PaperTable : public ::testing::TestWithParam<TableCase> {};

// The paper's settings: 3.75, 7.5 and 15 fps (ideal 0.00110, 0.00056, 0.00028 s/row with
// 240 rows), LED 2.5 to 103 Hz, d = 0; plus an LED near a multiple of the frame rate.
TEST_P(PaperTable, LineDelayWithinOnePercentAndDZero) {
  const TableCase c = GetParam();
  const Measured run = calibrate(paper_capture(c.fps, c.led_hz));
  expect_accurate(run, "fps " + std::to_string(c.fps) + ", LED " + std::to_string(c.led_hz) + " Hz");
  ASSERT_TRUE(run.r.zero_delay.has_value());
  EXPECT_TRUE(*run.r.zero_delay) << "blanking " << *run.r.blanking_s << " +- " << *run.r.blanking_sigma_s;
  EXPECT_NEAR(run.r.row_rate_hz, 240 * c.fps, 0.01 * 240 * c.fps);  // r = rows x fps
  // The seed (the paper's spectral peak) is within two frequency bins of the truth.
  EXPECT_NEAR(run.r.spectral_peak_cycles_per_row, c.led_hz * run.truth, 2.0 / 240);
  EXPECT_EQ(run.r.frames_used, 12);
}

INSTANTIATE_TEST_SUITE_P(
    Settings, PaperTable,
    ::testing::Values(TableCase{3.75, 2.5}, TableCase{3.75, 11}, TableCase{3.75, 20}, TableCase{3.75, 50},
                      TableCase{3.75, 103}, TableCase{7.5, 2.5}, TableCase{7.5, 11}, TableCase{7.5, 20},
                      TableCase{7.5, 50}, TableCase{7.5, 103}, TableCase{15, 11}, TableCase{15, 20},
                      TableCase{15, 50}, TableCase{15, 103}, TableCase{3.75, 27 * 3.75 + 0.05}));

// The brief's very low frequency: 0.66 bars per frame, fitted jointly across frames.
TEST(LedCalibration, BelowOneBarPerFrame) {
  const Measured run = calibrate(paper_capture(3.75, 2.5));
  EXPECT_NEAR(run.r.cycles_per_frame, 2.5 / 3.75, 0.01);
  EXPECT_EQ(run.r.model, LedModel::JointPerRow);
  EXPECT_LT(std::abs(run.err()), 0.001);
}

TEST(LedCalibration, DetectsVerticalBlanking) {
  for (double fps : {3.75, 7.5, 15.0}) {
    LedCaptureSpec s = paper_capture(fps, 50);
    s.readout_fraction = 0.8;  // 20% of the frame period is blanking
    const Measured run = calibrate(s);
    expect_accurate(run, "blanking at " + std::to_string(fps) + " fps");
    ASSERT_TRUE(run.r.zero_delay.has_value());
    EXPECT_FALSE(*run.r.zero_delay);
    EXPECT_NEAR(*run.r.blanking_s, 0.2 / fps, 3 * *run.r.blanking_sigma_s);
    EXPECT_NEAR(*run.r.blanking_s, 0.2 / fps, 0.01 / fps);
  }
}

// ---------------------------------------------------------------- robustness

struct Effect {
  const char* name;
  void (*apply)(LedCaptureSpec&);
  bool with_fps = true;
};

LedCaptureSpec robustness_base() {
  LedCaptureSpec s = paper_capture(7.5, 20);
  s.width = 64;
  s.frames = 8;
  s.exposure_s = 0;  // sharp bars unless an effect says otherwise
  s.vignetting = 0;
  s.noise = 1;
  return s;
}

void uneven(LedCaptureSpec& s) {
  s.vignetting = 0.6;   // 40% at the corners
  s.gradient_x = 0.8;   // 20% at the left edge, 180% at the right (saturated)
}
void gamma22(LedCaptureSpec& s) { s.gamma = 2.2; }
void saturated(LedCaptureSpec& s) { s.gain = 2.5; }  // the LED-on level clips at full scale
void long_exposure(LedCaptureSpec& s) { s.exposure_s = 3.25 / s.led_hz; }  // bars 14x weaker
void bayer(LedCaptureSpec& s) { s.colour = SensorColour::Bayer; }
void rgb(LedCaptureSpec& s) { s.colour = SensorColour::Rgb; }
void near_multiple(LedCaptureSpec& s) { s.led_hz = 7 * s.fps + 0.05; }  // bars frozen
void noisy(LedCaptureSpec& s) { s.noise = 25; }
void sixteen_bit(LedCaptureSpec& s) { s.sixteen_bit = true; }
void short_pulses(LedCaptureSpec& s) { s.duty = 0.1; }  // harmonics as strong as the fundamental
void combined(LedCaptureSpec& s) {
  uneven(s);
  gamma22(s);
  s.gain = 1.6;
  bayer(s);
  s.noise = 4;
  long_exposure(s);
}
void combined_near_multiple(LedCaptureSpec& s) {
  near_multiple(s);
  combined(s);
}

class Robustness : public ::testing::TestWithParam<Effect> {};

TEST_P(Robustness, LineDelayWithinOnePercent) {
  LedCaptureSpec s = robustness_base();
  GetParam().apply(s);
  const Measured run = calibrate(s, GetParam().with_fps);
  expect_accurate(run, GetParam().name);
  if (GetParam().with_fps) {
    EXPECT_TRUE(run.r.zero_delay.value_or(false));
  }
}

INSTANTIATE_TEST_SUITE_P(
    Effects, Robustness,
    ::testing::Values(Effect{"uneven", uneven}, Effect{"gamma", gamma22}, Effect{"saturation", saturated},
                      Effect{"long_exposure", long_exposure}, Effect{"bayer", bayer},
                      Effect{"bayer_no_fps", bayer, false}, Effect{"rgb", rgb},
                      Effect{"near_multiple", near_multiple}, Effect{"noise", noisy},
                      Effect{"sixteen_bit", sixteen_bit}, Effect{"short_pulses_no_fps", short_pulses, false},
                      Effect{"combined", combined}, Effect{"combined_no_fps", combined, false},
                      Effect{"combined_near_multiple", combined_near_multiple}),
    [](const auto& info) { return std::string(info.param.name); });

// A consumer camera's single frame: 1920 x 1080 RGB, LED at 1 kHz, rows read in 30 ms of a
// 33.3 ms frame (nu = 0.0309 cycles/row, 33 bars), short exposure, vignetting, noise and
// JPEG-like blur.
TEST(LedCalibration, ConsumerCameraSingleFrame) {
  LedCaptureSpec s;
  s.width = 1920;
  s.height = 1080;
  s.frames = 1;
  s.fps = 30;
  s.readout_fraction = 0.9;
  s.led_hz = 1000;
  s.exposure_s = 1.0 / 8000;
  s.colour = SensorColour::Rgb;
  s.vignetting = 0.5;
  s.noise = 3;
  s.blur_px = 1.2;
  const Measured run = calibrate(s);
  expect_accurate(run, "1080p");
  EXPECT_EQ(run.r.model, LedModel::PerFrame);
  EXPECT_FALSE(run.r.zero_delay.value_or(true));
  EXPECT_NEAR(*run.r.blanking_s, 0.1 / 30, 3 * *run.r.blanking_sigma_s);
  EXPECT_NEAR(run.r.cycles_per_frame, 1000 * 0.9 / 30, 0.3);
}

// The reported sigma is the actual scatter: over independent noise, the rms error divided
// by the mean sigma is near 1 (a low-contrast, noisy capture, where noise dominates).
TEST(LedCalibration, UncertaintyMatchesScatter) {
  LedCaptureSpec s = paper_capture(7.5, 20);
  s.width = 64;
  s.frames = 8;
  s.waveform = LedWaveform::Sine;
  s.exposure_s = 0;
  s.dark = 0.3;
  s.bright = 0.4;
  s.noise = 20;
  double sum_err2 = 0, sum_sigma = 0;
  const int n = 12;
  for (int i = 0; i < n; ++i) {
    s.seed = 100 + i;
    s.led_phase_cycles = 0.37 * i;
    const Measured run = calibrate(s);
    sum_err2 += run.err() * run.err();
    sum_sigma += run.sigma();
  }
  const double ratio = std::sqrt(sum_err2 / n) / (sum_sigma / n);
  RecordProperty("rms_error_over_sigma", std::to_string(ratio));
  EXPECT_GT(ratio, 0.6);
  EXPECT_LT(ratio, 1.6);
}

// ---------------------------------------------------------------- direction, timing, aliasing

TEST(LedCalibration, ReadoutDirectionFromKnownFrameTimes) {
  LedCaptureSpec s = robustness_base();
  s.readout = Readout::BottomToTop;
  const Measured up = calibrate(s);
  expect_accurate(up, "bottom to top");
  ASSERT_TRUE(up.r.readout.has_value());
  EXPECT_EQ(*up.r.readout, Readout::BottomToTop);
  EXPECT_LT(up.r.nu_cycles_per_row, 0);
  const Measured down = calibrate(robustness_base());
  ASSERT_TRUE(down.r.readout.has_value());
  EXPECT_EQ(*down.r.readout, Readout::TopToBottom);
  EXPECT_FALSE(calibrate(robustness_base(), false).r.readout.has_value());  // frames fitted alone
}

TEST(LedCalibration, TimestampsCarryDroppedFrames) {
  LedCaptureSpec s = robustness_base();
  s.dropped_frames = {3, 6};  // the six left still see the LED at three phases
  const Measured stamped = calibrate(s, false, true);
  expect_accurate(stamped, "timestamps");
  EXPECT_EQ(stamped.r.model, LedModel::JointPerRow);
  EXPECT_EQ(stamped.r.frames_used, 6);
}

// With --fps but frames missing, frame k no longer starts at k / fps: the joint fit fails,
// the frame-by-frame fit takes over, and says so.
TEST(LedCalibration, DroppedFramesWithoutTimestampsFallBack) {
  LedCaptureSpec s = robustness_base();
  s.frames = 12;
  s.dropped_frames = {3, 7, 8};
  const Measured run = calibrate(s);
  expect_accurate(run, "dropped frames");
  EXPECT_EQ(run.r.model, LedModel::PerFrame);
  EXPECT_TRUE(has_warning(run.r, "do not follow the given frame times"));
}

// An LED faster than half the row rate aliases: nu = 0.556 is seen as 1 - 0.556 = 0.444.
// The line delay reported is the alias's, and the warning offers the true one.
TEST(LedCalibration, WarnsOfAliasing) {
  LedCaptureSpec s = robustness_base();
  s.fps = 15;
  s.led_hz = 2000;
  s.exposure_s = 0;
  s.waveform = LedWaveform::Sine;
  const Measured run = calibrate(s);
  const double nu = s.led_hz * s.line_delay_s();
  EXPECT_NEAR(run.r.line_delay_s, (1 - nu) / s.led_hz, 1e-3 * run.truth);
  EXPECT_TRUE(has_warning(run.r, "aliasing ambiguity"));
  EXPECT_TRUE(has_warning(run.r, "0.0002778 s"));  // the truth, 1 / (240 x 15)
}

TEST(LedCalibration, WarnsOfLowContrast) {
  LedCaptureSpec s = robustness_base();
  s.dark = 0.30;
  s.bright = 0.305;  // 1.3 grey levels of bars
  const Measured run = calibrate(s);
  EXPECT_TRUE(has_warning(run.r, "low contrast"));
  EXPECT_LT(std::abs(run.err()), 0.01);
}

TEST(LedCalibration, IgnoresFramesBeyondTheLimit) {
  LedCaptureSpec s = robustness_base();
  LedCalibrationOptions o;
  o.led_hz = s.led_hz;
  o.fps = s.fps;
  o.max_frames = 4;
  const LedCalibrationResult r = estimate(synthesize_led_capture(s), o);
  EXPECT_EQ(r.frames_used, 4);
  EXPECT_TRUE(has_warning(r, "4 frames beyond the first 4"));
}

TEST(LedCalibration, LedFrequencyAccuracyAddsToTheUncertainty) {
  const LedCapture cap = synthesize_led_capture(robustness_base());
  LedCalibrationOptions o;
  o.led_hz = 20;
  o.fps = 7.5;
  const double base = estimate(cap, o).line_delay_sigma_s;
  o.led_hz_accuracy = 1e-3;  // 1000 ppm dominates
  const LedCalibrationResult r = estimate(cap, o);
  EXPECT_NEAR(r.line_delay_sigma_s, std::hypot(base, 1e-3 * r.line_delay_s), 1e-3 * r.line_delay_sigma_s);
}

// ---------------------------------------------------------------- errors

TEST(LedCalibration, FlatImageHasNoModulation) {
  LedCaptureSpec s = robustness_base();
  s.dark = s.bright = 0.4;
  EXPECT_THROW(calibrate(s), LedCalibrationError);
  s.noise = 3;  // noise alone is not an LED either
  try {
    calibrate(s);
    FAIL() << "noise taken for bars";
  } catch (const LedCalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("no LED modulation found"), std::string::npos) << e.what();
  }
}

// An exposure of exactly three LED periods averages every row to the same level.
TEST(LedCalibration, ExposureOfWholePeriodsErasesTheBars) {
  LedCaptureSpec s = robustness_base();
  s.exposure_s = 3 / s.led_hz;
  EXPECT_THROW(calibrate(s), LedCalibrationError);
}

// LED at exactly 1/6 of the frame rate with 0.17 bars per frame: every row sees the LED at
// the same six phases, the square wave's edges fall on one row, and its duty cycle trades
// off against the line delay. The capture cannot tell; the error says why.
TEST(LedCalibration, SimpleFractionOfTheFrameRateIsUndetermined) {
  try {
    calibrate(paper_capture(15, 2.5));
    FAIL() << "a line delay was claimed";
  } catch (const LedCalibrationError& e) {
    EXPECT_NE(std::string(e.what()).find("1/6 of the frame rate"), std::string::npos) << e.what();
  }
}

TEST(LedCalibration, RejectsMismatchedFramesAndBadOptions) {
  LedCalibrationOptions o;
  o.led_hz = 20;
  LedCalibrator cal(o);
  Image a(64, 48, PixelFormat::Mono8), b(64, 40, PixelFormat::Mono8), c(64, 48, PixelFormat::Rgb8);
  cal.add_frame(a.view());
  EXPECT_THROW(cal.add_frame(b.view()), std::invalid_argument);
  EXPECT_THROW(cal.add_frame(c.view()), std::invalid_argument);
  Image tiny(64, 8, PixelFormat::Mono8);
  EXPECT_THROW(LedCalibrator(o).add_frame(tiny.view()), std::invalid_argument);
  o.led_hz = 0;
  EXPECT_THROW(LedCalibrator{o}, std::invalid_argument);
  o.led_hz = 20;
  o.fps = -1;
  EXPECT_THROW(LedCalibrator{o}, std::invalid_argument);
  o.fps.reset();
  EXPECT_THROW(LedCalibrator(o).estimate(), LedCalibrationError);  // no frames
}

}  // namespace
