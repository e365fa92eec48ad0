// Per-row source positions from the map, and the resampling of a frame through them: the
// part of rectification that runs for every frame, allocation-free.
#include <algorithm>
#include <cmath>
#include <cstring>

#include "dsp/rectify/bilinear_sampling.hpp"
#include "dsp/rectify/cell_affines.hpp"
#include "dsp/rectify/fixed_point.hpp"
#include "dsp/rectify/node_row_lerp.hpp"
#include "dsp/rectify/rs_rectifier.hpp"

namespace rsd::dsp {

using namespace rectify_detail;

// ---- Per-row source positions and resampling ---------------------------------------------

namespace {

void linear_segment(const Affine& a, std::int32_t* xs, std::int32_t* ys, int count) {
  // Running sums (a vector induction, no multiplies), wrapping like the sampler's.
  std::uint32_t x = static_cast<std::uint32_t>(a.ax), y = static_cast<std::uint32_t>(a.ay);
  for (int k = 0; k < count; ++k, x += static_cast<std::uint32_t>(a.sx), y += static_cast<std::uint32_t>(a.sy))
    xs[k] = static_cast<std::int32_t>(x), ys[k] = static_cast<std::int32_t>(y);
}

}  // namespace

// Grid g's node columns interpolated to image row y (linear in y between two node rows; y is
// fractional for the rows of 4:2:0 chroma); returns the cell row.
int Rectifier::interpolate_row(const Grid& g, double y, NodeRow& r) const {
  const Level& L = levels_[g.level];
  const int j = std::min(static_cast<int>(y) >> L.shift, L.ny - 2);
  const double wy = (y - j * L.spacing) / L.spacing;
  const std::size_t top = static_cast<std::size_t>(j) * L.nx, bot = top + L.nx;
  auto lerp = [&](const std::vector<double>& v, std::vector<double>& out, std::vector<std::int32_t>* fixed) {
    lerp_node_row(&v[top], &v[bot], wy, L.nx, out.data(), fixed ? fixed->data() : nullptr);
  };
  if (plane_) lerp(g.plane.x, r.px, &r.fpx), lerp(g.plane.y, r.py, &r.fpy);
  if (need_infinite_) lerp(g.inf.x, r.ix, &r.fix), lerp(g.inf.y, r.iy, &r.fiy);
  if (plane_ && need_infinite_) lerp(g.rho, r.rho, nullptr);  // picks the branch in kink cells only
  return j;
}

namespace {

// The samples [c0, c1) of plane g whose image positions lie in cell i of a grid of `spacing`
// (a cell spans an even number of pixels, so every half-resolution plane has half of them in each).
void cell_columns(int spacing, int i, const SamplePlane& g, int& c0, int& c1) {
  const int shift = g.scale_x - 1;  // scale 1 or 2: a shift, not a division, per cell
  c0 = (i * spacing) >> shift, c1 = std::min(((i + 1) * spacing) >> shift, g.width);
}

}  // namespace

// Source positions of plane g's samples on image row y into s.xs, s.ys (16.16 in the plane's
// coordinates; kSentinel where the output is black). A split cell's pixels come from its fine cells.
void Rectifier::generate_row(double y, const SamplePlane& g, RowScratch& s) const {
  const Level& L = levels_[coarse_.level];
  const int j = interpolate_row(coarse_, y, s.coarse);
  const int jf = refined_ && split_row_[j] ? interpolate_row(fine_, y, s.fine) : 0;
  for (int i = 0; i + 1 < L.nx; ++i) {
    if (!split(i, j)) {
      generate_cell(coarse_, s.coarse, j, i, g, s);
      continue;
    }
    for (int f = 2 * i; f <= std::min(2 * i + 1, levels_[fine_.level].nx - 2); ++f) generate_cell(fine_, s.fine, jf, f, g, s);
  }
}

// Cell (i, j) of grid g on the row whose node values r holds.
void Rectifier::generate_cell(const Grid& g, const NodeRow& r, int j, int i, const SamplePlane& p, RowScratch& s) const {
  const Level& L = levels_[g.level];
  int c0, c1;
  cell_columns(L.spacing, i, p, c0, c1);
  if (c0 >= c1) return;
  const std::uint8_t mode = g.cell_mode[static_cast<std::size_t>(j) * (L.nx - 1) + i];
  const PlaneScale scale(p);
  if (mode == kZero)
    std::fill(&s.xs[c0], &s.xs[c1], kSentinel), std::fill(&s.ys[c0], &s.ys[c1], kSentinel);
  else if (mode == kKink)
    kink_segment(g, r, i, c0, c1, p, s);
  else
    linear_segment(mode == kPlane ? cell_affine(r.fpx.data(), r.fpy.data(), i, L.shift, scale)
                                  : cell_affine(r.fix.data(), r.fiy.data(), i, L.shift, scale),
                   &s.xs[c0], &s.ys[c0], c1 - c0);
}

// A cell the horizon crosses: both branches are smooth there, so each is interpolated and the
// sign of the (interpolated) inverse depth picks, per pixel, the one the depth model means.
void Rectifier::kink_segment(const Grid& g, const NodeRow& r, int i, int c0, int c1, const SamplePlane& p,
                             RowScratch& s) const {
  const double sp = levels_[g.level].spacing;
  for (int c = c0; c < c1; ++c) {
    const double a = (p.scale_x * c + p.offset_x - i * sp) / sp;
    const bool plane = r.rho[i] + a * (r.rho[i + 1] - r.rho[i]) > 0;
    const std::vector<double>& X = plane ? r.px : r.ix;
    const std::vector<double>& Y = plane ? r.py : r.iy;
    s.xs[c] = to_fixed((X[i] + a * (X[i + 1] - X[i]) - p.offset_x) / p.scale_x);
    s.ys[c] = to_fixed((Y[i] + a * (Y[i + 1] - Y[i]) - p.offset_y) / p.scale_y);
  }
}

// Sample rows [j0, j1) of one plane with one band's scratch. Cells of 16 px and more are sampled
// straight from their affine segments (cell_affines, a row's cells at once), each run of
// consecutive cells of one grid and branch in one kernel call; narrower cells go through the
// row arrays, so that the kernels still see runs of 16 pixels. A split cell's row is its two
// fine cells'.
void Rectifier::remap_rows(const SamplePlane& src, const SamplePlane& dst, int j0, int j1, RowScratch& s) const {
  const Level& L = levels_[coarse_.level];
  const int kind = static_cast<int>(sample_kind(src));
  const auto row = sample_row_[kind];
  const auto cells = sample_cells_[kind];
  const PlaneScale scale(dst);
  struct Tier {  // one grid's cells on this row
    const Grid* g;
    NodeRow* r;
    int cell_n = 0, n_cells = 0, j = 0;
    const std::uint8_t* modes = nullptr;
  };
  auto tier = [&](const Grid& g, NodeRow& r) {
    const Level& G = levels_[g.level];
    Tier t{&g, &r};
    t.cell_n = G.spacing >> (dst.scale_x - 1);  // samples per cell (spacings are even)
    t.n_cells = std::min(G.nx - 1, (dst.width + t.cell_n - 1) / t.cell_n);  // those with samples of this plane
    return t;
  };
  Tier coarse = tier(coarse_, s.coarse), fine = refined_ ? tier(fine_, s.fine) : Tier{};
  auto prepare = [&](Tier& t, double y) {
    const Level& G = levels_[t.g->level];
    t.j = interpolate_row(*t.g, y, *t.r);
    t.modes = &t.g->cell_mode[static_cast<std::size_t>(t.j) * (G.nx - 1)];
    if (plane_) cell_affines(t.r->fpx.data(), t.r->fpy.data(), t.n_cells, G.shift, scale, t.r->plane_cells.data());
    if (need_infinite_) cell_affines(t.r->fix.data(), t.r->fiy.data(), t.n_cells, G.shift, scale, t.r->inf_cells.data());
  };
  for (int j = j0; j < j1; ++j) {
    std::uint8_t* out = dst.row(j);
    const double y = dst.scale_y * j + dst.offset_y;
    if (L.spacing < 16) {
      generate_row(y, dst, s);
      row(src, s.xs.data(), s.ys.data(), out, dst.width);
      continue;
    }
    prepare(coarse, y);
    const bool mixed = refined_ && split_row_[coarse.j];
    if (mixed) prepare(fine, y);
    const Tier* run_tier = nullptr;  // cells [first, first + run) of run_tier, of branch run_mode, not yet sampled
    int first = 0, run = 0;
    std::uint8_t run_mode = kZero;
    auto flush = [&] {
      if (run == 0) return;
      const int c0 = first * run_tier->cell_n, c1 = std::min((first + run) * run_tier->cell_n, dst.width);
      const NodeRow& r = *run_tier->r;
      cells(src, (run_mode == kPlane ? r.plane_cells : r.inf_cells).data() + first, run_tier->cell_n, c1 - c0,
            out + c0 * dst.step);
      run = 0;
    };
    auto cell = [&](const Tier& t, int i) {
      const std::uint8_t m = t.modes[i];
      if (m == kPlane || m == kInfinite) {  // the common case
        if (m != run_mode || &t != run_tier || first + run != i) flush(), run_mode = m, run_tier = &t, first = i;
        ++run;
        return;
      }
      flush();
      int c0, c1;
      cell_columns(levels_[t.g->level].spacing, i, dst, c0, c1);
      std::uint8_t* o = out + c0 * dst.step;
      if (m == kZero) {
        fill_samples(dst, o, c1 - c0);
      } else {
        kink_segment(*t.g, *t.r, i, c0, c1, dst, s);
        row(src, &s.xs[c0], &s.ys[c0], o, c1 - c0);
      }
    };
    for (int i = 0; i < coarse.n_cells; ++i) {
      if (mixed && split(i, coarse.j)) {
        for (int f = 2 * i; f < std::min(2 * i + 2, fine.n_cells); ++f) cell(fine, f);
        continue;
      }
      const std::uint8_t m = coarse.modes[i];
      if (m == run_mode && run_tier == &coarse && (m == kPlane || m == kInfinite)) {  // the common case: the run grows
        ++run;
        continue;
      }
      cell(coarse, i);
    }
    flush();
  }
}

// Every sample plane (image_planes.hpp) in bands of consecutive rows, one band per thread of
// the executor (the rows cost about the same).
void Rectifier::remap(const ImageView& src, const ImageView& dst) {
  if (!map_ready_) throw std::logic_error("Rectifier::remap: no map built");
  check_views(src, dst);
  struct Job {
    Rectifier* self;
    SamplePlane src[4], dst[4];
    int planes, bands;
  } job{this, {}, {}, 0, 0};
  job.planes = sample_planes(src, job.src);
  sample_planes(dst, job.dst);
  job.bands = executor_ ? std::clamp(RectifierConfig::bands_for(executor_->concurrency()), 1, static_cast<int>(bands_.size())) : 1;
  auto band = [](void* ctx, int b) {
    const Job& j = *static_cast<const Job*>(ctx);
    for (int p = 0; p < j.planes; ++p) {
      const int h = j.dst[p].height;
      j.self->remap_rows(j.src[p], j.dst[p], h * b / j.bands, h * (b + 1) / j.bands, j.self->bands_[b]);
    }
  };
  if (job.bands == 1) return band(&job, 0);
  executor_->run(job.bands, band, &job);
}

void Rectifier::map_row(int y, double* sx, double* sy) {
  if (!map_ready_) throw std::logic_error("Rectifier::map_row: no map built");
  RowScratch& s = bands_[0];
  SamplePlane unit;
  unit.width = out_.width;
  generate_row(y, unit, s);
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
  for (const ImageView* v : {&src, &dst})
    if (v->stride < static_cast<std::ptrdiff_t>(row_bytes(format_, v->width)) || (format_ == PixelFormat::I420 && v->stride % 2))
      throw std::invalid_argument("Rectifier: a view's stride is shorter than its rows (or odd, for I420)");
}

}  // namespace rsd::dsp
