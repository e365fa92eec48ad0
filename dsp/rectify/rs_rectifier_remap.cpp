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
  std::int32_t x = a.ax, y = a.ay;  // running sums: a vector induction, no multiplies
  for (int k = 0; k < count; ++k, x += a.sx, y += a.sy) xs[k] = x, ys[k] = y;
}

}  // namespace

// The node columns interpolated to row y (linear in y between two node rows); returns the
// cell row.
int Rectifier::interpolate_row(int y) {
  const Level& L = levels_[level_];
  const int j = std::min(y >> L.shift, L.ny - 2);
  const double wy = static_cast<double>(y - j * L.spacing) / L.spacing;
  const std::size_t top = static_cast<std::size_t>(j) * L.nx, bot = top + L.nx;
  auto lerp = [wy](const std::vector<double>& v, std::size_t a, std::size_t b) { return v[a] + wy * (v[b] - v[a]); };
  for (int i = 0; i < L.nx; ++i) {
    if (plane_) row_px_[i] = lerp(plane_b_.x, top + i, bot + i), row_py_[i] = lerp(plane_b_.y, top + i, bot + i);
    if (need_infinite_) row_ix_[i] = lerp(inf_b_.x, top + i, bot + i), row_iy_[i] = lerp(inf_b_.y, top + i, bot + i);
    row_rho_[i] = lerp(rho_, top + i, bot + i);
  }
  return j;
}

Rectifier::Affine Rectifier::cell_affine(int i, std::uint8_t mode) const {
  const std::vector<double>& X = mode == kPlane ? row_px_ : row_ix_;
  const std::vector<double>& Y = mode == kPlane ? row_py_ : row_iy_;
  return affine_between(X[i], Y[i], X[i + 1], Y[i + 1], levels_[level_].shift);
}

// Row y's source positions into xs_, ys_ (16.16; kSentinel where the output is black).
void Rectifier::generate_row(int y) {
  const Level& L = levels_[level_];
  const std::uint8_t* modes = &cell_mode_[static_cast<std::size_t>(interpolate_row(y)) * (L.nx - 1)];
  for (int i = 0; i + 1 < L.nx && i * L.spacing < out_.width; ++i) {
    const int x0 = i * L.spacing, count = std::min(L.spacing, out_.width - x0);
    if (modes[i] == kZero)
      std::fill_n(&xs_[x0], count, kSentinel), std::fill_n(&ys_[x0], count, kSentinel);
    else if (modes[i] == kKink)
      kink_segment(i, x0, count);
    else
      linear_segment(cell_affine(i, modes[i]), &xs_[x0], &ys_[x0], count);
  }
}

// A cell the horizon crosses: both branches are smooth there, so each is interpolated and the
// sign of the (interpolated) inverse depth picks, per pixel, the one the depth model means.
void Rectifier::kink_segment(int i, int x0, int count) {
  const double s = levels_[level_].spacing;
  for (int k = 0; k < count; ++k) {
    const double a = k / s;
    const bool plane = row_rho_[i] + a * (row_rho_[i + 1] - row_rho_[i]) > 0;
    const std::vector<double>& X = plane ? row_px_ : row_ix_;
    const std::vector<double>& Y = plane ? row_py_ : row_iy_;
    xs_[x0 + k] = to_fixed(X[i] + a * (X[i + 1] - X[i]));
    ys_[x0 + k] = to_fixed(Y[i] + a * (Y[i + 1] - Y[i]));
  }
}

// Cells of 16 px and more are sampled straight from their affine positions; narrower cells
// go through the row arrays, so that the kernels still see runs of 16 pixels.
void Rectifier::remap(const ImageView& src, const ImageView& dst) {
  if (!map_ready_) throw std::logic_error("Rectifier::remap: no map built");
  check_views(src, dst);
  const Level& L = levels_[level_];
  const int bpp = bytes_per_pixel(format_);
  for (int y = 0; y < out_.height; ++y) {
    std::uint8_t* out = dst.row(y);
    if (L.spacing < 16) {
      generate_row(y);
      sample_row_(src, xs_.data(), ys_.data(), out, out_.width);
      continue;
    }
    const std::uint8_t* modes = &cell_mode_[static_cast<std::size_t>(interpolate_row(y)) * (L.nx - 1)];
    for (int i = 0; i + 1 < L.nx && i * L.spacing < out_.width; ++i) {
      const int x0 = i * L.spacing, count = std::min(L.spacing, out_.width - x0);
      if (modes[i] == kZero) {
        std::memset(out + x0 * bpp, 0, static_cast<std::size_t>(count) * bpp);
      } else if (modes[i] == kKink) {
        kink_segment(i, x0, count);
        sample_row_(src, &xs_[x0], &ys_[x0], out + x0 * bpp, count);
      } else {
        sample_affine_(src, cell_affine(i, modes[i]), out + x0 * bpp, count);
      }
    }
  }
}

void Rectifier::map_row(int y, double* sx, double* sy) {
  if (!map_ready_) throw std::logic_error("Rectifier::map_row: no map built");
  generate_row(y);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (int x = 0; x < out_.width; ++x) {
    sx[x] = xs_[x] == kSentinel ? nan : xs_[x] / kFix;
    sy[x] = ys_[x] == kSentinel ? nan : ys_[x] / kFix;
  }
}

void Rectifier::check_views(const ImageView& src, const ImageView& dst) const {
  if (src.width != cam_.width || src.height != cam_.height || src.format != format_ || !src.data)
    throw std::invalid_argument("Rectifier: source view does not match the camera and format");
  if (dst.width != out_.width || dst.height != out_.height || dst.format != format_ || !dst.data)
    throw std::invalid_argument("Rectifier: destination view does not match the output camera and format");
}

}  // namespace rsd::dsp
