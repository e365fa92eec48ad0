// Synthetic captures of the paper's LED calibration set-up (Meingast, Geyer, Sastry 2005,
// Sec. "Calibration"): a lens-less sensor facing an LED that blinks at a known frequency.
//
// Every row is exposed at its own time (eq. (1), via RowTiming), so a blinking LED
// paints horizontal bars whose spatial frequency is nu = f_LED * line_delay cycles/row.
// The generator adds, one switch each, the nuisances a real capture has: uneven
// illumination (vignetting and a gradient across the columns), gamma, saturation, an
// exposure longer than the flash period, a Bayer mosaic or RGB output, additive noise,
// JPEG-like blur and 8-bit quantisation. It is the ground truth of the calibration tests
// and documentation; it is pure math (deterministic for a given seed, no I/O).
#pragma once

#include <cstdint>
#include <vector>

#include "dsp/core/image.hpp"
#include "dsp/geometry/row_timing.hpp"

namespace rsd::dsp {

enum class LedWaveform { Square, Sine };
enum class SensorColour { Mono, Bayer, Rgb };  // Bayer: an RGGB mosaic written as Mono8/16

struct LedCaptureSpec {
  // Sensor and timing.
  int width = 320, height = 240, frames = 16;
  double fps = 15;
  double readout_fraction = 1;  // frame readout time / frame period; 1: the paper's d = 0
  Readout readout = Readout::TopToBottom;
  double exposure_s = 0;        // row exposure; 0: each row samples the LED at its read time
  std::vector<int> dropped_frames;  // indices of frames not delivered (the others keep their times)

  // The LED (pulse generator).
  double led_hz = 20;
  LedWaveform waveform = LedWaveform::Square;
  double duty = 0.5;               // fraction of the period the LED is on (square wave)
  double led_phase_cycles = 0.13;  // LED phase at t = 0

  // Light on the sensor, linear, full scale 1: LED off gives `dark`, LED on `bright`.
  double dark = 0.08, bright = 0.7;
  double vignetting = 0;  // gain falls by this fraction at the corners (radial, quadratic)
  double gradient_x = 0;  // gain 1 - g at the left column to 1 + g at the right one
  double gain = 1;        // overall gain; > 1 drives the bright parts into saturation
  double gamma = 1;       // encoded = linear^(1/gamma), after clipping to full scale
  SensorColour colour = SensorColour::Mono;
  bool sixteen_bit = false;
  double noise = 0;       // Gaussian noise std, in 8-bit grey levels (scaled for 16 bit)
  double blur_px = 0;     // Gaussian blur sigma (JPEG-like loss of detail), after noise
  std::uint64_t seed = 1;

  double line_delay_s() const { return readout_fraction / (fps * height); }
  RowTiming timing() const;
};

struct LedCapture {
  std::vector<Image> frames;
  std::vector<double> times_s;  // start (first row read) of each delivered frame
};

LedCapture synthesize_led_capture(const LedCaptureSpec& spec);

// Mean LED brightness (0 off .. 1 on) over [t, t + e]; e = 0 gives the value at t.
double led_mean_brightness(const LedCaptureSpec& spec, double t, double e);

}  // namespace rsd::dsp
