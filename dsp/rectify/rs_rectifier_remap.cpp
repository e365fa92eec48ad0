// Per-row source positions from the map, and the resampling of a frame through them: the
// part of rectification that runs for every frame, allocation-free.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "dsp/rectify/bilinear_sampling.hpp"
#include "dsp/rectify/fixed_point.hpp"
#include "dsp/rectify/rs_rectifier.hpp"

namespace rsd::dsp {

using namespace rectify_detail;

// ---- Per-row source positions and resampling ---------------------------------------------

namespace {

// 16.16 start and per-pixel step of a cell segment from its two ends (one cell apart).
Affine affine_between(double x_l, double y_l, double x_r, double y_r, int shift) {
  const std::int32_t ax = to_fixed(x_l), ay = to_fixed(y_l);
  const std::int64_t half = (std::int64_t{1} << shift) >> 1;
  return {ax, ay, static_cast<std::int32_t>((std::int64_t{to_fixed(x_r)} - ax + half) >> shift),
          static_cast<std::int32_t>((std::int64_t{to_fixed(y_r)} - ay + half) >> shift)};
}

void linear_segment(const Affine& a, std::int32_t* xs, std::int32_t* ys, int count) {
  // Running sums (a vector induction, no multiplies), wrapping like the sampler's.
  std::uint32_t x = static_cast<std::uint32_t>(a.ax), y = static_cast<std::uint32_t>(a.ay);
  for (int k = 0; k < count; ++k, x += static_cast<std::uint32_t>(a.sx), y += static_cast<std::uint32_t>(a.sy))
    xs[k] = static_cast<std::int32_t>(x), ys[k] = static_cast<std::int32_t>(y);
}

}  // namespace

// The node columns interpolated to row y (linear in y between two node rows); returns the
// cell row.
int Rectifier::interpolate_row(int y, RowScratch& s) const {
  const Level& L = levels_[level_];
  const int j = std::min(y >> L.shift, L.ny - 2);
  const double wy = static_cast<double>(y - j * L.spacing) / L.spacing;
  const std::size_t top = static_cast<std::size_t>(j) * L.nx, bot = top + L.nx;
  auto lerp = [wy](const std::vector<double>& v, std::size_t a, std::size_t b) { return v[a] + wy * (v[b] - v[a]); };
  for (int i = 0; i < L.nx; ++i) {
    if (plane_) s.px[i] = lerp(plane_b_.x, top + i, bot + i), s.py[i] = lerp(plane_b_.y, top + i, bot + i);
    if (need_infinite_) s.ix[i] = lerp(inf_b_.x, top + i, bot + i), s.iy[i] = lerp(inf_b_.y, top + i, bot + i);
    s.rho[i] = lerp(rho_, top + i, bot + i);
  }
  return j;
}

Rectifier::Affine Rectifier::cell_affine(int i, std::uint8_t mode, const RowScratch& s) const {
  const std::vector<double>& X = mode == kPlane ? s.px : s.ix;
  const std::vector<double>& Y = mode == kPlane ? s.py : s.iy;
  return affine_between(X[i], Y[i], X[i + 1], Y[i + 1], levels_[level_].shift);
}

// Row y's source positions into s.xs, s.ys (16.16; kSentinel where the output is black).
void Rectifier::generate_row(int y, RowScratch& s) const {
  const Level& L = levels_[level_];
  const std::uint8_t* modes = &cell_mode_[static_cast<std::size_t>(interpolate_row(y, s)) * (L.nx - 1)];
  for (int i = 0; i + 1 < L.nx && i * L.spacing < out_.width; ++i) {
    const int x0 = i * L.spacing, count = std::min(L.spacing, out_.width - x0);
    if (modes[i] == kZero)
      std::fill_n(&s.xs[x0], count, kSentinel), std::fill_n(&s.ys[x0], count, kSentinel);
    else if (modes[i] == kKink)
      kink_segment(i, x0, count, s);
    else
      linear_segment(cell_affine(i, modes[i], s), &s.xs[x0], &s.ys[x0], count);
  }
}

// A cell the horizon crosses: both branches are smooth there, so each is interpolated and the
// sign of the (interpolated) inverse depth picks, per pixel, the one the depth model means.
void Rectifier::kink_segment(int i, int x0, int count, RowScratch& s) const {
  const double sp = levels_[level_].spacing;
  for (int k = 0; k < count; ++k) {
    const double a = k / sp;
    const bool plane = s.rho[i] + a * (s.rho[i + 1] - s.rho[i]) > 0;
    const std::vector<double>& X = plane ? s.px : s.ix;
    const std::vector<double>& Y = plane ? s.py : s.iy;
    s.xs[x0 + k] = to_fixed(X[i] + a * (X[i + 1] - X[i]));
    s.ys[x0 + k] = to_fixed(Y[i] + a * (Y[i + 1] - Y[i]));
  }
}

// Rows [y0, y1) with one band's scratch. Cells of 16 px and more are sampled straight from their
// affine positions; narrower cells go through the row arrays, so that the kernels still see
// runs of 16 pixels.
void Rectifier::remap_rows(const ImageView& src, const ImageView& dst, int y0, int y1, RowScratch& s) const {
  const Level& L = levels_[level_];
  const int bpp = bytes_per_pixel(format_);
  for (int y = y0; y < y1; ++y) {
    std::uint8_t* out = dst.row(y);
    if (L.spacing < 16) {
      generate_row(y, s);
      sample_row_(src, s.xs.data(), s.ys.data(), out, out_.width);
      continue;
    }
    const std::uint8_t* modes = &cell_mode_[static_cast<std::size_t>(interpolate_row(y, s)) * (L.nx - 1)];
    for (int i = 0; i + 1 < L.nx && i * L.spacing < out_.width; ++i) {
      const int x0 = i * L.spacing, count = std::min(L.spacing, out_.width - x0);
      if (modes[i] == kZero) {
        std::memset(out + x0 * bpp, 0, static_cast<std::size_t>(count) * bpp);
      } else if (modes[i] == kKink) {
        kink_segment(i, x0, count, s);
        sample_row_(src, &s.xs[x0], &s.ys[x0], out + x0 * bpp, count);
      } else {
        sample_affine_(src, cell_affine(i, modes[i], s), out + x0 * bpp, count);
      }
    }
  }
}

// Bands of consecutive rows, one per thread of the executor (the rows cost about the same).
void Rectifier::remap(const ImageView& src, const ImageView& dst) {
  if (!map_ready_) throw std::logic_error("Rectifier::remap: no map built");
  check_views(src, dst);
  const int bands = executor_ ? std::clamp(executor_->concurrency(), 1, static_cast<int>(bands_.size())) : 1;
  if (bands == 1) return remap_rows(src, dst, 0, out_.height, bands_[0]);
  struct Job {
    Rectifier* self;
    const ImageView *src, *dst;
    int bands;
  } job{this, &src, &dst, bands};
  executor_->run(bands, [](void* ctx, int band) {
    const Job& j = *static_cast<const Job*>(ctx);
    const int h = j.self->out_.height;
    j.self->remap_rows(*j.src, *j.dst, h * band / j.bands, h * (band + 1) / j.bands, j.self->bands_[band]);
  }, &job);
}

void Rectifier::map_row(int y, double* sx, double* sy) {
  if (!map_ready_) throw std::logic_error("Rectifier::map_row: no map built");
  RowScratch& s = bands_[0];
  generate_row(y, s);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int x = 0; x < out_.width; ++x) {
    sx[x] = s.xs[x] == kSentinel ? nan : s.xs[x] / kFix;
    sy[x] = s.ys[x] == kSentinel ? nan : s.ys[x] / kFix;
  }
}

void Rectifier::check_views(const ImageView& src, const ImageView& dst) const {
  if (src.width != cam_.width || src.height != cam_.height || src.format != format_ || !src.data)
    throw std::invalid_argument("Rectifier: source view does not match the camera and format");
  if (dst.width != out_.width || dst.height != out_.height || dst.format != format_ || !dst.data)
    throw std::invalid_argument("Rectifier: destination view does not match the output camera and format");
}

}  // namespace rsd::dsp
