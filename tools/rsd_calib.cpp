// rsd-calib: calibrations of a rolling-shutter camera.
//
//   rsd-calib led --freq HZ [--fps FPS] [--json] INPUT...
//     The line delay, row rate r and frame readout time from frames of a lens-less sensor
//     facing an LED blinking at a known frequency, and whether the inter-frame delay d is
//     zero (Meingast, Geyer, Sastry 2005, Sec. "Calibration"; dsp/calib/led_calibration.hpp).
//   rsd-calib synth-led --out DIR [...]
//     Writes a synthetic capture of that set-up (dsp/calib/led_capture_synthesis.hpp), the ground
//     truth of the tests and of docs/led-calibration.md.
//   rsd-calib import-lens PROFILE.json --width W --height H -o CAL
//     A gyroflow lens profile as a calibration file (tools/calib/import_lens.hpp).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "tools/calib/import_lens.hpp"
#include "tools/common/cli_util.hpp"
#include "dsp/calib/led_calibration.hpp"
#include "dsp/calib/led_capture_synthesis.hpp"
#include "tools/common/frame_sources.hpp"
#include "formats/calibration_v1.hpp"
#include "formats/image_file.hpp"

namespace formats = rsd::formats;
using namespace rsd::dsp;
using namespace rsd::tools;
namespace fs = std::filesystem;

namespace {

constexpr const char* kDescription =
    "rsd-calib: calibrations of a rolling-shutter camera (Meingast, Geyer, Sastry 2005).\n"
    "  led        line delay, row rate and frame readout time from frames of a sensor facing\n"
    "             an LED that blinks at a known frequency; whether the inter-frame delay d is 0\n"
    "  synth-led  write a synthetic LED capture (for tests and trials)\n"
    "  import-lens  a calibration file from a gyroflow lens profile (a fisheye lens, the readout)\n"
    "Run 'rsd-calib SUBCOMMAND --help' for the options.\n"
    "Exit status: 0 on success, 2 on bad arguments, 1 on other errors (unreadable images,\n"
    "no LED modulation found).";

// ---------------------------------------------------------------- options

struct LedOptions {
  double freq = 0;
  double fps = 0;
  bool fps_given = false;
  bool json = false;
  double accuracy_ppm = 0;
  int max_frames = 240;
  std::vector<std::string> inputs;
  std::string channel = "RSD_RAW";
  int live_frames = 60;
  std::string write_calibration, calibration_in;
};

struct SynthOptions {
  std::string out;
  double freq = 20, fps = 7.5, readout_fraction = 1, exposure = 0, duty = 0.5, phase = 0.13;
  int frames = 16, width = 320, height = 240;
  bool sine = false, sixteen_bit = false, bottom_to_top = false;
  double dark = 0.08, bright = 0.7, vignetting = 0, gradient = 0, gain = 1, gamma = 1, noise = 0, blur = 0;
  std::string colour = "mono";
  int seed = 1;
};

CLI::App* add_led_command(CLI::App& app, LedOptions& o) {
  CLI::App* led = app.add_subcommand(
      "led",
      "Line delay from frames of a lens-less sensor facing an LED blinking at --freq.\n"
      "INPUT: image files (PNG, PGM; RGB is reduced to luminance, a Bayer mosaic may be\n"
      "given as a grey image) or directories of them (read in natural name order:\n"
      "frame2 before frame10); or an LCM log of bot_core.image_t frames (--channel);\n"
      "or a live camera: live:aravis:ADDRESS, live:v4l2:/dev/videoN, live:libcamera[:ID]\n"
      "(--frames of them). With --fps, frame k is taken to start at k / fps: the\n"
      "joint model, and the verdict on d. Without it, frames are fitted one by one and\n"
      "each must show at least 1.5 bars.");
  led->add_option("--freq", o.freq, "LED (pulse generator) frequency (Hz)")
      ->required()->check(positive("hertz"));
  led->add_option("--fps", o.fps, "Frame rate (frames/s) of consecutive frames")->check(positive("frames per second"));
  led->add_option("--freq-accuracy", o.accuracy_ppm,
                  "Accuracy of --freq (ppm); added to the uncertainty")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  led->add_option("--max-frames", o.max_frames, "Use at most this many frames")
      ->check(int_range(1, 100000))->capture_default_str();
  led->add_flag("--json", o.json,
                "Print JSON: frame_readout_s, line_delay_s, row_rate_hz, blanking_s\n"
                "(null without --fps), uncertainty_s (1-sigma, of line_delay_s);\n"
                "warnings go to stderr");
  led->add_option("--channel", o.channel, "LCM log input: the image channel")->capture_default_str();
  led->add_option("--frames", o.live_frames, "Live input: frames to capture")->check(int_range(1, 100000))->capture_default_str();
  led->add_option("--write-calibration", o.write_calibration,
                  "Write the line delay (and the readout direction when the data show it) as an\n"
                  "rsd-calibration/1 file (docs/formats/calibration-v1.md)");
  led->add_option("--calibration", o.calibration_in,
                  "With --write-calibration: the camera's calibration to copy, line delay replaced\n"
                  "(without it the file's intrinsics are placeholders)")
      ->check(CLI::ExistingFile);
  led->add_option("INPUT", o.inputs, "Image files or directories, an LCM log, or live:DRIVER:DEVICE")->required();
  return led;
}

// A number in (0, 1]: a duty cycle or the readout's share of the frame period.
CLI::Validator fraction() {
  return text_check(
      [](const std::string& s) {
        const auto x = parse_number(s);
        return x && *x > 0 && *x <= 1;
      },
      "expected a number in (0, 1]", "(0, 1]", "FRACTION");
}

CLI::App* add_synth_command(CLI::App& app, SynthOptions& o) {
  CLI::App* s = app.add_subcommand(
      "synth-led",
      "Write a synthetic capture of a lens-less sensor facing a blinking LED to\n"
      "DIR/frame_NNNN.png; prints the true timing.");
  s->add_option("--out", o.out, "Directory to write (created if missing)")->required();
  s->add_option("--freq", o.freq, "LED frequency (Hz)")->check(positive("hertz"))->capture_default_str();
  s->add_option("--fps", o.fps, "Frame rate (frames/s)")->check(positive("frames per second"))->capture_default_str();
  s->add_option("--frames", o.frames, "Number of frames")->check(int_range(1, 10000))->capture_default_str();
  s->add_option("--width", o.width, "Width (pixels)")->check(int_range(2, 20000))->capture_default_str();
  s->add_option("--height", o.height, "Height = rows read (pixels)")->check(int_range(16, 20000))->capture_default_str();
  s->add_option("--readout-fraction", o.readout_fraction, "Frame readout time / frame period (1: d = 0)")
      ->check(fraction())->capture_default_str();
  s->add_flag("--bottom-to-top", o.bottom_to_top, "Read the rows bottom to top");
  s->add_option("--exposure", o.exposure, "Row exposure (s)")->check(CLI::NonNegativeNumber)->capture_default_str();
  s->add_option("--duty", o.duty, "LED duty cycle (square wave)")->check(fraction())->capture_default_str();
  s->add_option("--phase", o.phase, "LED phase at t = 0 (cycles)")->check(finite_number("cycles"))->capture_default_str();
  s->add_flag("--sine", o.sine, "Sinusoidal LED instead of a square wave");
  s->add_option("--dark", o.dark, "Light with the LED off (fraction of full scale)")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  s->add_option("--bright", o.bright, "Light with the LED on (fraction of full scale)")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  s->add_option("--vignetting", o.vignetting, "Gain fall-off at the corners (fraction)")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  s->add_option("--gradient", o.gradient, "Gain gradient across the columns (+-fraction)")
      ->check(CLI::Range(0.0, 1.0))->capture_default_str();
  s->add_option("--gain", o.gain, "Overall gain (> 1 saturates)")->check(positive("times"))->capture_default_str();
  s->add_option("--gamma", o.gamma, "Encoding gamma")->check(positive("exponent"))->capture_default_str();
  s->add_option("--colour", o.colour, "mono, bayer (RGGB mosaic, grey file) or rgb")
      ->check(CLI::IsMember({"mono", "bayer", "rgb"}))->capture_default_str();
  s->add_flag("--sixteen-bit", o.sixteen_bit, "16-bit grey PNG");
  s->add_option("--noise", o.noise, "Gaussian noise (8-bit grey levels)")->check(CLI::NonNegativeNumber)->capture_default_str();
  s->add_option("--blur", o.blur, "Gaussian blur sigma (pixels)")->check(CLI::NonNegativeNumber)->capture_default_str();
  s->add_option("--seed", o.seed, "Noise seed")->check(int_range(0, 1000000000))->capture_default_str();
  return s;
}

// ---------------------------------------------------------------- led

LedCalibrationOptions calibration_options(const LedOptions& o) {
  LedCalibrationOptions c;
  c.led_hz = o.freq;
  if (o.fps_given) c.fps = o.fps;
  c.max_frames = o.max_frames;
  c.led_hz_accuracy = o.accuracy_ppm * 1e-6;
  return c;
}

// Feeds every frame of the source to the calibrator; errors name the frame.
LedCalibrationResult calibrate(FrameSource& src, const LedCalibrationOptions& opt) {
  LedCalibrator cal(opt);
  std::string first;
  while (std::optional<SourceFrame> f = src.next()) {
    try {
      cal.add_frame(f->image.view(), f->timestamp_s);
    } catch (const std::invalid_argument& e) {
      throw std::runtime_error(f->name + ": " + e.what() + (first.empty() ? "" : " (" + first + ")"));
    }
    if (first.empty()) first = f->name;
  }
  try {
    return cal.estimate();
  } catch (const LedCalibrationError& e) {
    throw std::runtime_error(src.description() + " (" + std::to_string(cal.frames()) + " frames): " + e.what());
  }
}

// "x +- sigma" (times scale), both to the decimal of sigma's second significant digit.
std::string plus_minus(double x, double sigma, double scale) {
  if (!(sigma > 0) || !std::isfinite(sigma)) return format_number(x * scale, 7) + " +- " + format_number(sigma * scale);
  const int decimals = std::clamp(1 - static_cast<int>(std::floor(std::log10(sigma * scale))), 0, 15);
  std::string v = format_fixed(x * scale, decimals);
  if (v.find_first_not_of("-0.") == std::string::npos && v[0] == '-') v.erase(0, 1);  // no "-0.000"
  return v + " +- " + format_fixed(sigma * scale, decimals);
}

std::string verdict(const LedCalibrationResult& r) {
  if (!r.zero_delay) return "unknown: give --fps to compare r with rows x fps";
  if (*r.zero_delay) return "d = 0 within uncertainty: the readout fills the frame period (r = rows x fps)";
  if (*r.blanking_s > 0)
    return "d > 0: the readout takes " + format_number(100 * r.frame_readout_s / *r.frame_period_s, 4) +
           "% of the frame period (vertical blanking)";
  return "inconsistent: the readout is longer than the frame period (check --fps and --freq)";
}

void print_timing(const LedCalibrationResult& r, const LedOptions& o) {
  std::cout << "Spatial frequency  nu = " << plus_minus(r.nu_cycles_per_row, r.nu_sigma, 1)
            << " cycles/row (" << format_number(r.cycles_per_frame, 4) << " bars per frame); spectral peak "
            << format_number(r.spectral_peak_cycles_per_row, 5) << " cycles/row\n"
            << "Line delay         " << plus_minus(r.line_delay_s, r.line_delay_sigma_s, 1e6) << " us/row\n"
            << "Row rate r         " << plus_minus(r.row_rate_hz, r.row_rate_sigma_hz, 1) << " rows/s";
  if (o.fps_given) std::cout << "  (rows x fps = " << format_number(r.rows * o.fps, 7) << ")";
  std::cout << "\nFrame readout      " << plus_minus(r.frame_readout_s, r.frame_readout_sigma_s, 1e3) << " ms\n";
  if (r.blanking_s)
    std::cout << "Blanking d         " << plus_minus(*r.blanking_s, *r.blanking_sigma_s, 1e3) << " ms\n";
  std::cout << "Verdict on d       " << verdict(r) << "\n";
}

void print_text(const LedCalibrationResult& r, const LedOptions& o) {
  std::cout << "rsd-calib led: " << r.frames_used << (r.frames_used == 1 ? " frame of " : " frames of ") << r.width << " x " << r.rows << " ("
            << describe_inputs(o.inputs) << "), LED " << format_number(o.freq, 8) << " Hz"
            << (o.fps_given ? ", " + format_number(o.fps, 8) + " fps" : std::string(", frame rate not given"))
            << "\nModel              " << to_string(r.model) << "\nColumns used       " << r.columns_used
            << " of " << r.width << " (weighted by bar contrast)\n";
  print_timing(r, o);
  std::cout << "Readout direction  " << (r.readout ? std::string(to_string(*r.readout)) : "not determined") << "\n"
            << "Contrast           modulation depth " << format_number(100 * r.modulation_depth, 3)
            << "%, signal/noise " << format_number(r.snr, 3) << " per sample\n";
  if (r.warnings.empty()) std::cout << "Warnings           none\n";
  for (const std::string& w : r.warnings) std::cout << "Warning            " << w << "\n";
}

void print_json(const LedCalibrationResult& r) {
  std::ostringstream o;
  o << "{\n  \"frame_readout_s\": " << json_number(r.frame_readout_s)
    << ",\n  \"line_delay_s\": " << json_number(r.line_delay_s)
    << ",\n  \"row_rate_hz\": " << json_number(r.row_rate_hz)
    << ",\n  \"blanking_s\": " << (r.blanking_s ? json_number(*r.blanking_s) : "null")
    << ",\n  \"uncertainty_s\": " << json_number(r.line_delay_sigma_s) << "\n}\n";
  std::cout << o.str();
  for (const std::string& w : r.warnings) std::cerr << "rsd-calib: warning: " << w << "\n";
}

// The measured line delay into a calibration: a copy of the camera's (`in`, checked to be for
// frames of this size), or one with placeholder intrinsics, said so in its source and on stderr.
void write_led_calibration(const LedCalibrationResult& r, const LedOptions& o) {
  formats::Calibration c;
  if (!o.calibration_in.empty()) {
    c = formats::read_calibration(o.calibration_in);
    formats::require_resolution(c, r.width, r.rows);
    c.source = "rsd-calib led (line delay) over " + o.calibration_in + (c.source.empty() ? "" : " (" + c.source + ")");
  } else {
    c.cam = CameraModel::from_hfov(r.width, r.rows, 60.0 * M_PI / 180.0);
    c.source = "rsd-calib led (line delay); intrinsics are placeholders, not calibrated";
    std::cerr << "rsd-calib: warning: " << o.write_calibration
              << ": the intrinsics are placeholders (give --calibration with the camera's calibration to keep them)\n";
  }
  c.line_delay_s = r.line_delay_s;
  if (r.readout) c.readout = *r.readout;
  c.sigma["line_delay_s"] = {r.line_delay_sigma_s};
  formats::write_calibration(o.write_calibration, c);
}

int run_led(const LedOptions& o) {
  if (!o.calibration_in.empty() && o.write_calibration.empty()) throw UsageError("--calibration goes with --write-calibration");
  if (!o.write_calibration.empty()) require_writable(o.write_calibration, "--write-calibration");
  const auto src = open_frame_source(o.inputs, {o.channel, o.live_frames});
  const LedCalibrationResult r = calibrate(*src, calibration_options(o));
  if (o.json)
    print_json(r);
  else
    print_text(r, o);
  if (!o.write_calibration.empty()) write_led_calibration(r, o);
  return 0;
}

// ---------------------------------------------------------------- synth-led

LedCaptureSpec synth_spec(const SynthOptions& o) {
  LedCaptureSpec s;
  s.width = o.width;
  s.height = o.height;
  s.frames = o.frames;
  s.fps = o.fps;
  s.readout_fraction = o.readout_fraction;
  s.readout = o.bottom_to_top ? Readout::BottomToTop : Readout::TopToBottom;
  s.exposure_s = o.exposure;
  s.led_hz = o.freq;
  s.waveform = o.sine ? LedWaveform::Sine : LedWaveform::Square;
  s.duty = o.duty;
  s.led_phase_cycles = o.phase;
  s.dark = o.dark;
  s.bright = o.bright;
  s.vignetting = o.vignetting;
  s.gradient_x = o.gradient;
  s.gain = o.gain;
  s.gamma = o.gamma;
  s.colour = o.colour == "bayer" ? SensorColour::Bayer : o.colour == "rgb" ? SensorColour::Rgb : SensorColour::Mono;
  s.sixteen_bit = o.sixteen_bit;
  s.noise = o.noise;
  s.blur_px = o.blur;
  s.seed = static_cast<std::uint64_t>(o.seed);
  return s;
}

int run_synth(const SynthOptions& o) {
  if (o.sixteen_bit && o.colour == "rgb") throw UsageError("--sixteen-bit: only grey images can be 16-bit");
  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (!fs::is_directory(o.out)) throw UsageError("--out: cannot create directory '" + o.out + "'");
  const LedCaptureSpec spec = synth_spec(o);
  LedCapture cap = synthesize_led_capture(spec);
  for (size_t k = 0; k < cap.frames.size(); ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04zu.png", k);
    formats::write_png((fs::path(o.out) / name).string(), cap.frames[k].view());
  }
  const double readout = spec.line_delay_s() * spec.height;
  std::cout << "Wrote " << cap.frames.size() << " frames of " << o.width << " x " << o.height << " (" << o.colour
            << ") to " << o.out << ": LED " << format_number(o.freq, 8) << " Hz, " << format_number(o.fps, 8)
            << " fps\nTrue line delay " << format_number(spec.line_delay_s(), 9) << " s, frame readout "
            << format_number(readout, 9) << " s, blanking d " << format_number(1 / o.fps - readout, 9)
            << " s, nu " << format_number(o.freq * spec.line_delay_s(), 9) << " cycles/row\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("rsd-calib", [&] {
    CLI::App app{kDescription};
    app.require_subcommand(1);
    LedOptions led;
    SynthOptions synth;
    ImportLensOptions lens;
    CLI::App* led_cmd = add_led_command(app, led);
    add_synth_command(app, synth);
    CLI::App* lens_cmd = add_import_lens_command(app, lens);
    if (const auto rc = parse_command_line(app, argc, argv)) return *rc;
    led.fps_given = led_cmd->count("--fps") > 0;
    if (lens_cmd->parsed()) return run_import_lens(lens);
    return led_cmd->parsed() ? run_led(led) : run_synth(synth);
  });
}
