// LED-flicker calibration (paper section 5): the estimator's steps and the public API. The
// steps' parts live beside it: led_stack (the spatio-temporal image), led_spectrum, led_seeds,
// led_sinusoid_model and led_fit, sharing led_internal.hpp.
#include "dsp/calib/led_calibration.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "dsp/calib/led_internal.hpp"
#include "dsp/core/statistics.hpp"

namespace rsd::dsp {

namespace led {

Plan make_plan(const LedCalibrationOptions& o, const std::vector<std::optional<double>>& times, int h) {
  const int K = static_cast<int>(times.size());
  const bool stamped = std::all_of(times.begin(), times.end(), [](const auto& t) { return t.has_value(); });
  std::vector<double> t;
  Plan p;
  if (stamped) {
    for (const auto& ts : times) t.push_back(*ts - *times.front());
    std::vector<double> dt;
    for (int k = 1; k < K; ++k) dt.push_back(t[k] - t[k - 1]);
    if (o.fps) p.period = 1 / *o.fps;
    else if (!dt.empty() && median(dt) > 0) p.period = median(dt);
  } else if (o.fps) {
    for (int k = 0; k < K; ++k) t.push_back(k / *o.fps);
    p.period = 1 / *o.fps;
  }
  p.omega.assign(K, 0.0);
  if (K >= 2 && !t.empty()) {
    for (int k = 0; k < K; ++k) {  // wrapped before scaling: t_k f may be large
      const double u = o.led_hz * t[k];
      p.omega[k] = 2 * kPi * (u - std::floor(u));
    }
    const bool moving = K >= 3 && phase_diversity(p.omega) >= kMinDiversity;
    p.model = moving ? LedModel::JointPerRow : LedModel::JointSmooth;
  }
  // The readout cannot be slower than the frame period: |nu| <= f * period / rows.
  if (p.period) p.nu_hi = std::min(kMaxNu, kReadoutSlack * o.led_hz * *p.period / h);
  return p;
}

// A flat capture (or one whose rows never change) has nothing to fit.
void require_variation(const Stack& st) {
  const double mean = st.s.mean();
  const double var = (st.s.array() - mean).square().mean();
  if (!(var > 1e-12 * (mean * mean + 1)))
    throw LedCalibrationError("no LED modulation found: the image is flat (no variation between rows)");
}

Seed find_seed(const Stack& st, const Plan& plan) {
  if (plan.model == LedModel::JointPerRow) return seed_per_row(st, plan);
  Seed s = seed_spectral(st, plan);
  if (s.peak.over_floor < kPeakOverFloor)
    throw LedCalibrationError(
        "no LED modulation found: no horizontal bars repeating at least " + fmt(kMinCyclesSmooth) +
        " times per frame (with unknown frame times, or an LED frequency near a multiple of the frame rate, "
        "the bars must be seen within single frames; give several consecutive frames and --fps for slower bars)");
  return s;
}

struct Outcome {
  Fit fit;
  Seed seed;
  std::optional<Readout> readout;
};

// Fits `m` (from its starting point) with the harmonics that are present; a quick fit is
// one solve, without the model-truncation check.
Fit fit_present(Model m, bool quick) {
  m = with_orders(m, present_orders(m));
  if (!quick) return fit_checked(m);
  return fit_model(m);
}

Outcome fit_per_row(const Stack& st, const Plan& plan, const Seed& seed, bool quick) {
  Model m = build_model(st, plan, constant_basis(static_cast<int>(st.s.cols())));
  m.nu = seed.nu;
  m.phase[0] = seed.phi;
  solve_linear(m, Linear::Envelope);
  set_orders(m, identifiable_orders(m, candidate_orders(plan, m.nu)));
  Outcome o{fit_present(m, quick), seed, std::nullopt};
  o.readout = o.fit.nu >= 0 ? Readout::TopToBottom : Readout::BottomToTop;
  return o;
}

// Smooth models. Joint smooth tries both signs of nu: the frames' small phase advance
// tells the readout direction when it is large enough to matter.
Outcome fit_smooth(const Stack& st, const Plan& plan, const Seed& seed, bool quick) {
  const int n = static_cast<int>(st.s.cols());
  Model m = build_model(st, plan, spline_basis(n, segments_for(std::abs(seed.nu) * n)));
  set_orders(m, candidate_orders(plan, seed.nu));
  if (plan.model == LedModel::PerFrame) {
    grid_start(m, seed.nu, n);
    return {fit_present(m, quick), seed, std::nullopt};
  }
  Model neg = m;
  const double rss_pos = grid_start(m, seed.nu, n), rss_neg = grid_start(neg, -seed.nu, n);
  Outcome o{fit_present(rss_pos <= rss_neg ? m : neg, quick), seed, std::nullopt};
  if (std::abs(rss_pos - rss_neg) > 25 * o.fit.s2())  // the better sign fits by 5 sigma
    o.readout = o.fit.nu >= 0 ? Readout::TopToBottom : Readout::BottomToTop;
  return o;
}

Outcome fit_plan(const Stack& st, const Plan& plan, bool quick = false) {
  const Seed seed = find_seed(st, plan);
  return plan.model == LedModel::JointPerRow ? fit_per_row(st, plan, seed, quick)
                                             : fit_smooth(st, plan, seed, quick);
}

bool acceptable(const Fit& f) {
  return f.f_statistic() >= kMinF && f.nu_sigma / std::abs(f.nu) <= kMaxRelSigma;
}

// A joint fit trusts the frame times. When the frames also show enough bars to be fitted
// one by one, that fit (which ignores the times) checks them: if the joint fit found
// nothing, or the frame-by-frame fit explains the data clearly better and disagrees, the
// frames are not consecutive at that rate (dropped frames, a wrong --fps): it is used.
void cross_check(const Stack& st, const Plan& plan, Outcome& out, std::vector<std::string>& warnings) {
  if (plan.model == LedModel::PerFrame) return;
  Plan alone = plan;
  alone.model = LedModel::PerFrame;
  std::fill(alone.omega.begin(), alone.omega.end(), 0.0);
  Outcome other;
  try {
    other = fit_plan(st, alone, true);
  } catch (const LedCalibrationError&) {
    return;
  }
  if (!acceptable(other.fit)) return;
  const double gap = std::abs(std::abs(other.fit.nu) - std::abs(out.fit.nu));
  const double sigma = std::hypot(other.fit.nu_sigma, out.fit.nu_sigma);
  const bool disagree = gap > 5 * sigma && other.fit.s2() < 0.8 * out.fit.s2();
  if (acceptable(out.fit) && !disagree) return;
  warnings.push_back("the frames do not follow the given frame times (dropped frames or a wrong frame rate?): "
                     "the joint fit gave nu = " + fmt(std::abs(out.fit.nu), 6) +
                     " cycles/row; the frame-by-frame fit was used");
  out = fit_plan(st, alone);
}

// The bars must stand out of the noise (F test of the sinusoid against offsets alone),
// and the data must pin nu down.
void require_signal(const Fit& f, const LedCalibrationOptions& o, const Plan& plan) {
  if (!(f.f_statistic() >= kMinF))
    throw LedCalibrationError("no LED modulation found: the best sinusoid (nu = " + fmt(std::abs(f.nu)) +
                              " cycles/row) does not stand out of the noise (F = " + fmt(f.f_statistic(), 3) + ")");
  const double rel = f.nu_sigma / std::abs(f.nu);
  if (rel <= kMaxRelSigma) return;
  std::string why;
  if (plan.period) {
    const double ratio = o.led_hz * *plan.period;
    for (int q = 1; q <= 8 && why.empty(); ++q)
      if (std::abs(ratio * q - std::round(ratio * q)) < 1e-3 * q)
        why = "; the LED frequency is " + fmt(std::round(ratio * q), 3) + "/" + std::to_string(q) +
              " of the frame rate, so every row sees the LED at only " + std::to_string(q) +
              " phases and a non-sinusoidal LED's harmonics alias onto its fundamental: use an LED frequency "
              "that is not a simple fraction of the frame rate";
  }
  if (why.empty()) why = "; use more frames, more bars per frame (a higher LED frequency) or more contrast";
  throw LedCalibrationError("LED bars found (nu = " + fmt(std::abs(f.nu)) + " cycles/row), but the capture does "
                            "not determine the line delay: relative uncertainty " + fmt(100 * rel, 3) + "%" + why);
}

// Alias candidates: on a row grid nu and k +- nu are the same bars. They matter when the
// frame period allows a readout slow enough for them.
void alias_warnings(const LedCalibrationOptions& o, const Plan& plan, double nu, int h,
                    std::vector<std::string>& w) {
  const double a = std::abs(nu);
  if (!plan.period) {
    if (a > 0.25)
      w.push_back("aliasing ambiguity: nu = " + fmt(a) + " is close to the row Nyquist frequency 0.5; if the LED "
                  "is faster than half the row rate, the line delay may be (1 - nu)/f = " + fmt((1 - a) / o.led_hz) +
                  " s (give --fps to rule it out)");
    return;
  }
  const double limit = kReadoutSlack * o.led_hz * *plan.period / h;
  std::string alts;
  for (int k = 1; k <= 4; ++k)
    for (double c : {k - a, k + a})
      if (c <= limit) alts += (alts.empty() ? "" : ", ") + fmt(c / o.led_hz) + " s";
  if (!alts.empty())
    w.push_back("aliasing ambiguity: the LED is fast enough for aliased bars (k +- nu cycles/row) to fit the frame "
                "period; other possible line delays: " + alts);
}

void quality_warnings(const Fit& f, const Outcome& out, std::vector<std::string>& w) {
  if (out.seed.peak.harmonic > 1)
    w.push_back("the strongest spectral peak is harmonic " + std::to_string(out.seed.peak.harmonic) +
                " of the LED (square-wave drive); its fundamental was used");
  if (f.depth < 0.02)
    w.push_back("low contrast: the bars modulate the image by only " + fmt(100 * f.depth, 2) + "%");
  const double snr = f.amplitude / std::sqrt(f.s2());
  if (snr < 1) w.push_back("low signal-to-noise ratio: bar amplitude / residual rms = " + fmt(snr, 2));
}

void timing_warnings(const LedCalibrationResult& r, const Plan& plan, const LedCalibrationOptions& o,
                     std::vector<std::string>& w) {
  if (r.model == LedModel::JointSmooth) {
    const double u = o.led_hz * plan.period.value_or(0);
    w.push_back("the LED frequency is close to a multiple of the frame rate (the bars move " +
                fmt(u - std::round(u), 2) + " cycles per frame): frozen bars, smooth illumination model used");
  }
  if (r.blanking_s && *r.blanking_s < -o.zero_delay_sigmas * *r.blanking_sigma_s)
    w.push_back("the readout (" + fmt(r.frame_readout_s * 1e3) + " ms) is longer than the frame period (" +
                fmt(*r.frame_period_s * 1e3) + " ms): check the LED frequency and the frame rate");
}

LedCalibrationResult assemble(const Outcome& out, const Plan& plan, const LedCalibrationOptions& o, int h) {
  const Fit& f = out.fit;
  LedCalibrationResult r;
  r.model = f.kind;
  r.readout = out.readout;
  r.nu_cycles_per_row = out.readout ? f.nu : std::abs(f.nu);
  r.nu_sigma = f.nu_sigma;
  r.spectral_peak_cycles_per_row = std::abs(out.seed.peak.nu);
  r.line_delay_s = std::abs(f.nu) / o.led_hz;
  // nu's own uncertainty, the model floor and the LED frequency's accuracy, all relative.
  const double rel = std::sqrt(std::pow(f.nu_sigma / f.nu, 2) + kModelFloor * kModelFloor +
                               o.led_hz_accuracy * o.led_hz_accuracy);
  r.line_delay_sigma_s = rel * r.line_delay_s;
  r.row_rate_hz = 1 / r.line_delay_s;
  r.row_rate_sigma_hz = r.line_delay_sigma_s / (r.line_delay_s * r.line_delay_s);
  r.frame_readout_s = h * r.line_delay_s;
  r.frame_readout_sigma_s = h * r.line_delay_sigma_s;
  r.rows = h;
  r.cycles_per_frame = std::abs(f.nu) * h;
  r.modulation_depth = f.depth;
  r.snr = f.amplitude / std::sqrt(f.s2());
  if (plan.period) {  // the paper's test: r = rows * fps means d = 0
    r.frame_period_s = *plan.period;
    r.blanking_s = *plan.period - r.frame_readout_s;
    r.blanking_sigma_s = r.frame_readout_sigma_s;
    r.zero_delay = std::abs(*r.blanking_s) <= o.zero_delay_sigmas * *r.blanking_sigma_s;
  }
  return r;
}

}  // namespace led

using namespace led;

std::string_view to_string(LedModel m) {
  switch (m) {
    case LedModel::JointPerRow: return "joint (known frame times, per-row offset and gain)";
    case LedModel::JointSmooth: return "joint (known frame times, smooth illumination)";
    case LedModel::PerFrame: return "frame by frame (own phase per frame, smooth illumination)";
  }
  return "";
}

LedCalibrator::LedCalibrator(const LedCalibrationOptions& opt) : opt_(opt) {
  if (!(opt.led_hz > 0) || !std::isfinite(opt.led_hz))
    throw std::invalid_argument("the LED frequency must be a positive number of hertz");
  if (opt.fps && (!(*opt.fps > 0) || !std::isfinite(*opt.fps)))
    throw std::invalid_argument("the frame rate must be a positive number of frames per second");
  if (opt.max_frames < 1) throw std::invalid_argument("max_frames must be at least 1");
  if (!(opt.led_hz_accuracy >= 0)) throw std::invalid_argument("the LED frequency accuracy must be >= 0");
}

void LedCalibrator::add_frame(const ImageView& f, std::optional<double> timestamp_s) {
  if (width_ == 0) {
    if (f.height < 16 || f.width < 2)
      throw std::invalid_argument("frame is " + std::to_string(f.width) + " x " + std::to_string(f.height) +
                                  ": at least 2 columns and 16 rows are needed");
    width_ = f.width;
    height_ = f.height;
    format_ = f.format;
    // Even block widths keep both columns of a Bayer pair in the same block.
    block_width_ = 2 * std::max(1, (f.width + 2 * kMaxBlocks - 1) / (2 * kMaxBlocks));
    blocks_ = std::max(1, f.width / block_width_);
    block_width_ = std::min(block_width_, f.width);
  } else if (f.width != width_ || f.height != height_ || f.format != format_) {
    throw std::invalid_argument("frame is " + std::to_string(f.width) + " x " + std::to_string(f.height) +
                                (f.format != format_ ? " with another pixel format" : "") + ", the first was " +
                                std::to_string(width_) + " x " + std::to_string(height_));
  }
  if (frames() >= opt_.max_frames) {
    ++ignored_;
    return;
  }
  std::vector<double> prof(static_cast<size_t>(blocks_) * height_, 0.0);
  for (int y = 0; y < height_; ++y) {
    const std::uint8_t* row = f.row(y);
    for (int b = 0; b < blocks_; ++b) {
      double sum = 0;
      for (int x = b * block_width_; x < (b + 1) * block_width_; ++x) sum += luminance(f, row, x);
      prof[static_cast<size_t>(b) * height_ + y] = sum;
    }
  }
  profiles_.push_back(std::move(prof));
  times_.push_back(timestamp_s);
}

LedCalibrationResult LedCalibrator::estimate() const {
  if (profiles_.empty()) throw LedCalibrationError("no frames to calibrate from");
  const Plan plan = make_plan(opt_, times_, height_);
  Stack st = make_stack(profiles_, std::vector<double>(blocks_, 1.0), height_);
  require_variation(st);
  // Pass 1 finds the bars with every column; pass 2 weights the columns by their bars.
  const std::vector<double> w = block_weights(profiles_, blocks_, height_, plan, find_seed(st, plan).nu);
  st = make_stack(profiles_, w, height_);
  Outcome out = fit_plan(st, plan);
  std::vector<std::string> warnings;
  cross_check(st, plan, out, warnings);
  require_signal(out.fit, opt_, plan);
  LedCalibrationResult r = assemble(out, plan, opt_, height_);
  r.frames_used = frames();
  r.width = width_;
  r.columns_used = block_width_ * static_cast<int>(std::count_if(w.begin(), w.end(), [](double x) { return x > 0; }));
  if (ignored_ > 0)
    warnings.push_back(std::to_string(ignored_) + " frames beyond the first " + std::to_string(opt_.max_frames) +
                       " were ignored");
  alias_warnings(opt_, plan, out.fit.nu, height_, warnings);
  quality_warnings(out.fit, out, warnings);
  timing_warnings(r, plan, opt_, warnings);
  r.warnings = std::move(warnings);
  return r;
}

LedCalibrationResult calibrate_led(const std::vector<ImageView>& frames, const LedCalibrationOptions& opt) {
  LedCalibrator cal(opt);
  for (const ImageView& f : frames) cal.add_frame(f);
  return cal.estimate();
}

}  // namespace rsd::dsp
