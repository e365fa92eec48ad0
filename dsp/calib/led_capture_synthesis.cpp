#include "dsp/calib/led_capture_synthesis.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace rsd::dsp {

namespace {

// A small deterministic normal generator (SplitMix64 + Marsaglia's polar method): the
// same noise on every platform, unlike std::normal_distribution whose algorithm is
// unspecified; and no trigonometry, which matters for 1080p RGB frames.
class Normal {
 public:
  explicit Normal(std::uint64_t seed) : state_(seed) {}
  double operator()() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u, v, s;
    do {
      u = 2 * uniform() - 1;
      v = 2 * uniform() - 1;
      s = u * u + v * v;
    } while (s >= 1 || s == 0);
    const double f = std::sqrt(-2 * std::log(s) / s);
    spare_ = v * f;
    has_spare_ = true;
    return u * f;
  }

 private:
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::uint64_t state_;
  double spare_ = 0;
  bool has_spare_ = false;
};

// Integral of the LED waveform from 0 to phase u (in cycles): a square wave that is on
// for the first `duty` of each cycle, or the raised cosine 0.5 + 0.5 cos(2 pi u).
double waveform_integral(const LedCaptureSpec& s, double u) {
  if (s.waveform == LedWaveform::Sine) return 0.5 * u + std::sin(2 * std::numbers::pi * u) / (4 * std::numbers::pi);
  const double whole = std::floor(u);
  return whole * s.duty + std::min(u - whole, s.duty);
}

// Illumination gain at a pixel: vignetting (radial, quadratic) times a gradient across
// the columns, the paper's "unable to achieve even distribution of exposure over the
// length of the scanline".
double illumination_gain(const LedCaptureSpec& s, int x, int y) {
  const double cx = 0.5 * (s.width - 1), cy = 0.5 * (s.height - 1);
  const double r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (cx * cx + cy * cy);
  const double across = s.width > 1 ? 2.0 * x / (s.width - 1) - 1 : 0;
  return s.gain * (1 - s.vignetting * r2) * (1 + s.gradient_x * across);
}

// Relative response of colour channel c (0 R, 1 G, 2 B) to a green LED.
double channel_gain(int c) {
  static constexpr double kGain[3] = {0.45, 1.0, 0.3};
  return kGain[c];
}

// The colour filter over pixel (x, y) of an RGGB mosaic.
int bayer_channel(int x, int y) {
  if (y % 2 == 0) return x % 2 == 0 ? 0 : 1;
  return x % 2 == 0 ? 1 : 2;
}

// One separable Gaussian pass of a float plane, along rows or columns; borders clamped.
void blur_pass(std::vector<double>& plane, int w, int h, double sigma, bool along_x) {
  const int radius = static_cast<int>(std::ceil(3 * sigma));
  std::vector<double> k(2 * radius + 1);
  double sum = 0;
  for (int i = -radius; i <= radius; ++i) sum += k[i + radius] = std::exp(-0.5 * i * i / (sigma * sigma));
  for (double& v : k) v /= sum;
  const int n = along_x ? w : h, lines = along_x ? h : w;
  const size_t step = along_x ? 1 : w;
  std::vector<double> line(n + 2 * radius);
  for (int l = 0; l < lines; ++l) {
    double* p = plane.data() + (along_x ? static_cast<size_t>(l) * w : l);
    for (int i = 0; i < n + 2 * radius; ++i) line[i] = p[std::clamp(i - radius, 0, n - 1) * step];
    for (int i = 0; i < n; ++i) {
      double acc = 0;
      for (int j = 0; j <= 2 * radius; ++j) acc += k[j] * line[i + j];
      p[i * step] = acc;
    }
  }
}

void check_spec(const LedCaptureSpec& s) {
  if (s.width < 2 || s.height < 2 || s.frames < 1) throw std::invalid_argument("LED capture: bad size");
  if (!(s.fps > 0) || !(s.led_hz > 0) || !(s.readout_fraction > 0))
    throw std::invalid_argument("LED capture: fps, LED frequency and readout fraction must be > 0");
  if (!(s.duty > 0 && s.duty <= 1) || !(s.gamma > 0) || s.exposure_s < 0 || s.blur_px < 0)
    throw std::invalid_argument("LED capture: bad duty, gamma, exposure or blur");
}

// One channel plane of frame k in output units (0..255 or 0..65535, unquantised):
// light -> clip (saturation) -> gamma -> noise -> blur.
std::vector<double> render_plane(const LedCaptureSpec& s, const std::vector<double>& led_row,
                                 int channel, Normal& noise) {
  const double full = s.sixteen_bit ? 65535 : 255, noise_scale = full / 255;
  std::vector<double> plane(static_cast<size_t>(s.width) * s.height);
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      const int c = s.colour == SensorColour::Bayer ? bayer_channel(x, y) : channel;
      const double light = s.dark + (s.bright - s.dark) * led_row[y];
      const double lin = std::clamp(illumination_gain(s, x, y) * channel_gain(c) * light, 0.0, 1.0);
      const double encoded = s.gamma == 1 ? lin : std::pow(lin, 1 / s.gamma);
      plane[static_cast<size_t>(y) * s.width + x] = full * encoded + (s.noise > 0 ? s.noise * noise_scale * noise() : 0);
    }
  if (s.blur_px > 0) {
    blur_pass(plane, s.width, s.height, s.blur_px, true);
    blur_pass(plane, s.width, s.height, s.blur_px, false);
  }
  return plane;
}

// Quantises channel plane `c` of `nc` into the image.
void store_plane(const std::vector<double>& plane, int c, int nc, Image& img) {
  const bool deep = img.format == PixelFormat::Mono16;
  const double full = deep ? 65535 : 255;
  for (size_t i = 0; i < plane.size(); ++i) {
    const double q = std::clamp(std::round(plane[i]), 0.0, full);
    if (deep)
      reinterpret_cast<std::uint16_t*>(img.data.data())[i] = static_cast<std::uint16_t>(q);
    else
      img.data[i * nc + c] = static_cast<std::uint8_t>(q);
  }
}

Image render_frame(const LedCaptureSpec& s, double t_frame, Normal& noise) {
  const RowTiming timing = s.timing();
  std::vector<double> led_row(s.height);
  for (int y = 0; y < s.height; ++y)  // rows are exposed from their read time on
    led_row[y] = led_mean_brightness(s, t_frame + timing.row_time(y), s.exposure_s);
  const bool rgb = s.colour == SensorColour::Rgb;
  const PixelFormat format = rgb ? PixelFormat::Rgb8 : s.sixteen_bit ? PixelFormat::Mono16 : PixelFormat::Mono8;
  Image img(s.width, s.height, format);
  const int nc = rgb ? 3 : 1;
  for (int c = 0; c < nc; ++c) store_plane(render_plane(s, led_row, rgb ? c : 1, noise), c, nc, img);
  return img;
}

}  // namespace

RowTiming LedCaptureSpec::timing() const {
  RowTiming t;
  t.height = height;
  t.frame_rate_hz = fps;
  t.line_delay_s = line_delay_s();
  t.readout = readout;
  t.exposure_s = exposure_s;
  return t;
}

double led_mean_brightness(const LedCaptureSpec& s, double t, double e) {
  const double u = s.led_hz * t + s.led_phase_cycles;
  if (e <= 0) {  // instantaneous: the waveform itself
    if (s.waveform == LedWaveform::Sine) return 0.5 + 0.5 * std::cos(2 * std::numbers::pi * u);
    return u - std::floor(u) < s.duty ? 1.0 : 0.0;
  }
  const double du = s.led_hz * e;
  return (waveform_integral(s, u + du) - waveform_integral(s, u)) / du;
}

LedCapture synthesize_led_capture(const LedCaptureSpec& spec) {
  check_spec(spec);
  LedCapture cap;
  Normal noise(spec.seed);
  for (int k = 0; k < spec.frames; ++k) {
    if (std::find(spec.dropped_frames.begin(), spec.dropped_frames.end(), k) != spec.dropped_frames.end())
      continue;
    const double t = k / spec.fps;
    cap.frames.push_back(render_frame(spec, t, noise));
    cap.times_s.push_back(t);
  }
  return cap;
}

}  // namespace rsd::dsp
