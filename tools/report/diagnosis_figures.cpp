#include "tools/report/diagnosis_figures.hpp"

#include <plplot.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "tools/common/cli_util.hpp"
#include "tools/report/plot_page.hpp"

namespace rsd::tools {

using namespace rsd::dsp;

namespace {

enum Colour : PLINT { kWhite = 0, kBlack, kLightBlue, kLightRed, kBlue, kRed, kLightGrey, kGrey };

void open_page(const std::string& file, int w, int h) {
  open_plot_page(file, w, h,
                 {{kWhite, 255, 255, 255}, {kBlack, 0, 0, 0}, {kLightBlue, 140, 170, 240}, {kLightRed, 245, 160, 150},
                  {kBlue, 0, 50, 200}, {kRed, 200, 20, 20}, {kLightGrey, 215, 215, 215}, {kGrey, 100, 100, 100}});
}

struct Bins {
  std::vector<PLFLT> x, du, dv, rms;
};

// Means of du and dv and the per-coordinate RMS in equal-width bins of x (inliers only;
// bins with fewer than 5 observations are left out).
Bins binned(const std::vector<double>& x, const Residuals& res, double lo, double hi, int nb) {
  std::vector<double> su(nb, 0), sv(nb, 0), s2(nb, 0), c(nb, 0);
  for (size_t k = 0; k < x.size(); ++k) {
    if (!res.in[k]) continue;
    const int b = std::clamp(static_cast<int>((x[k] - lo) / (hi - lo) * nb), 0, nb - 1);
    su[b] += res.r[k].x(), sv[b] += res.r[k].y(), s2[b] += res.r[k].squaredNorm(), c[b] += 1;
  }
  Bins out;
  for (int b = 0; b < nb; ++b)
    if (c[b] >= 5) {
      out.x.push_back(lo + (b + 0.5) * (hi - lo) / nb);
      out.du.push_back(su[b] / c[b]);
      out.dv.push_back(sv[b] / c[b]);
      out.rms.push_back(std::sqrt(s2[b] / (2 * c[b])));
    }
  return out;
}

void line(const std::vector<PLFLT>& x, const std::vector<PLFLT>& y, PLINT colour, PLFLT width, PLINT style) {
  if (x.size() < 2) return;
  plcol0(colour);
  plwidth(width);
  pllsty(style);
  plline(static_cast<PLINT>(x.size()), x.data(), y.data());
  pllsty(1);
  plwidth(1);
}

// A scatter of at most ~2000 inliers per coordinate (every k-th), drawn under the bin lines.
void scatter(const std::vector<double>& x, const Residuals& res) {
  const size_t stride = std::max<size_t>(1, x.size() / 2000);
  std::vector<PLFLT> xs, us, vs;
  for (size_t k = 0; k < x.size(); k += stride)
    if (res.in[k]) xs.push_back(x[k]), us.push_back(res.r[k].x()), vs.push_back(res.r[k].y());
  plssym(0, 0.45);
  plcol0(kLightBlue);
  plpoin(static_cast<PLINT>(xs.size()), xs.data(), us.data(), 17);
  plcol0(kLightRed);
  plpoin(static_cast<PLINT>(xs.size()), xs.data(), vs.data(), 17);
  plssym(0, 1.0);
}

void residual_panel(const Figures& f, const std::vector<double>& x, const Residuals& res, double lo, double hi,
                    double range, double y0, double y1, const std::string& title, const std::string& xlabel,
                    bool bottom) {
  plvpor(0.07, 0.76, y0, y1);
  plwind(lo, hi, -range, range);
  plcol0(kLightGrey);
  plbox("g", 0, 0, "g", 0, 0);
  scatter(x, res);
  const Bins b = binned(x, res, lo, hi, 24);
  std::vector<PLFLT> xs = {lo, hi}, plus = {f.sigma, f.sigma}, minus = {-f.sigma, -f.sigma}, zero = {0, 0};
  line(xs, zero, kGrey, 1, 1);
  line(xs, plus, kGrey, 1.5, 2);
  line(xs, minus, kGrey, 1.5, 2);
  line(b.x, b.du, kBlue, 3, 1);
  line(b.x, b.dv, kRed, 3, 1);
  line(b.x, b.rms, kBlack, 3, 1);
  plcol0(kBlack);
  plschr(0, 0.9);
  plbox(bottom ? "bcnst" : "bcst", 0, 0, "bcnstv", 0, 0);
  if (bottom) pllab(xlabel.c_str(), "", "");
  plmtex("l", 4.0, 0.5, 0.5, "residual (px)");
  plschr(0, 1.0);
  plmtex("t", 0.8, 0.0, 0.0, title.c_str());
}

void legend_notes(double sigma) {
  plvpor(0.775, 0.995, 0.1, 0.9);
  plwind(0, 1, 0, 1);
  plschr(0, 0.78);
  const std::pair<PLINT, std::string> notes[] = {
      {kLightBlue, "dots: du (u, right)"},
      {kLightRed, "dots: dv (v, down)"},
      {kBlue, "line: bin mean of du"},
      {kRed, "line: bin mean of dv"},
      {kBlack, "line: bin RMS per coord."},
      {kGrey, "dashed: +-#gs, #gs = " + format_number(sigma, 3) + " px"},
      {kGrey, "outliers (> 5 robust #gs)"},
      {kGrey, "are left out"}};
  double y = 0.95;
  for (const auto& [c, t] : notes) {
    plcol0(c);
    plptex(0.02, y, 1, 0, 0, t.c_str());
    y -= 0.06;
  }
  plschr(0, 1.0);
}

// Mean residual per image cell, drawn as an arrow from the cell centre.
struct CellMeans {
  int nx, ny;
  std::vector<Eigen::Vector2d> mean;
  std::vector<double> rms;  // per coordinate
  std::vector<int> count;
};

CellMeans cell_means(const DiagnosisModel& m, const Residuals& res, int nx, int ny) {
  const CameraModel& cam = m.recording().nominal.cam;
  CellMeans c{nx, ny, std::vector<Eigen::Vector2d>(nx * ny, Eigen::Vector2d::Zero()), std::vector<double>(nx * ny, 0),
              std::vector<int>(nx * ny, 0)};
  for (int i = 0; i < m.size(); ++i) {
    if (!res.in[i]) continue;
    const Eigen::Vector2d px = m.observed(i);
    const int cx = std::clamp(static_cast<int>(px.x() / cam.width * nx), 0, nx - 1);
    const int cy = std::clamp(static_cast<int>(px.y() / cam.height * ny), 0, ny - 1);
    c.mean[cy * nx + cx] += res.r[i], c.rms[cy * nx + cx] += res.r[i].squaredNorm(), c.count[cy * nx + cx] += 1;
  }
  for (int k = 0; k < nx * ny; ++k)
    if (c.count[k] > 0) c.mean[k] /= c.count[k], c.rms[k] = std::sqrt(c.rms[k] / (2 * c.count[k]));
  return c;
}

void arrow(double x, double y, double dx, double dy) {
  const double len = std::hypot(dx, dy);
  if (len <= 0) return;
  pljoin(x, y, x + dx, y + dy);
  const double head = 0.3 * len, a = 0.45;
  const double ux = -dx / len, uy = -dy / len;
  for (double s : {a, -a})
    pljoin(x + dx, y + dy, x + dx + head * (ux * std::cos(s) - uy * std::sin(s)),
           y + dy + head * (ux * std::sin(s) + uy * std::cos(s)));
}

// Cells shaded by their residual RMS (white 0, dark red at `rms_max`), mean-residual arrows on top.
void map_panel(const DiagnosisModel& m, const CellMeans& c, double scale, double rms_max, double x0, double x1,
               const std::string& title, const std::string& scales) {
  const CameraModel& cam = m.recording().nominal.cam;
  plvpas(x0, x1, 0.10, 0.80, static_cast<double>(cam.height) / cam.width);
  plwind(0, cam.width, cam.height, 0);  // v down, as in the image
  plcol0(kLightGrey);
  const double cw = static_cast<double>(cam.width) / c.nx, ch = static_cast<double>(cam.height) / c.ny;
  for (int j = 0; j < c.ny; ++j)
    for (int i = 0; i < c.nx; ++i) {
      const int k = j * c.nx + i;
      if (c.count[k] < 3) continue;
      PLFLT xs[4] = {i * cw, (i + 1) * cw, (i + 1) * cw, i * cw}, ys[4] = {j * ch, j * ch, (j + 1) * ch, (j + 1) * ch};
      plcol1(std::clamp(c.rms[k] / rms_max, 0.0, 1.0));
      plfill(4, xs, ys);
    }
  plcol0(kLightGrey);
  for (int k = 1; k < c.nx; ++k) pljoin(k * cw, 0, k * cw, cam.height);
  for (int k = 1; k < c.ny; ++k) pljoin(0, k * ch, cam.width, k * ch);
  plwidth(2);
  for (int j = 0; j < c.ny; ++j)
    for (int i = 0; i < c.nx; ++i) {
      const int k = j * c.nx + i;
      if (c.count[k] < 3) continue;
      const double x = (i + 0.5) * cw, y = (j + 0.5) * ch;
      plcol0(kBlack);
      PLFLT px = x, py = y;
      plssym(0, 0.4);
      plpoin(1, &px, &py, 17);
      plcol0(kBlue);
      arrow(x, y, scale * c.mean[k].x(), scale * c.mean[k].y());
    }
  plwidth(1);
  plcol0(kBlack);
  plschr(0, 0.85);
  plbox("bcnst", 0, 0, "bcnstv", 0, 0);
  pllab("u (px)", "v (px)", "");
  plmtex("t", 0.8, 0.0, 0.0, scales.c_str());
  plschr(0, 1.0);
  plmtex("t", 2.3, 0.0, 0.0, title.c_str());
}

// The arrow scale (px of residual per px of image) and shade limit that suit one panel.
std::pair<double, double> map_scales(const CellMeans& c, double cell) {
  double longest = 0, rms_max = 0;
  for (size_t k = 0; k < c.count.size(); ++k)
    if (c.count[k] >= 3) longest = std::max(longest, c.mean[k].norm()), rms_max = std::max(rms_max, c.rms[k]);
  // The longest arrow spans 0.9 cells.
  return {longest > 0 ? 0.9 * cell / longest : 1.0, std::max(rms_max, 1e-9)};
}

std::string map_scale_text(double cell, double scale, double rms_max) {
  return "arrow 1 cell wide = " + format_number(cell / scale, 3) + " px; darkest = " + format_number(rms_max, 3) +
         " px RMS";
}

// Residual axis: the 99th percentile of the inlier components, at least 4 sigma.
double residual_range(const Residuals& res, double sigma) {
  std::vector<double> a;
  for (size_t k = 0; k < res.r.size(); ++k)
    if (res.in[k]) a.push_back(std::abs(res.r[k].x())), a.push_back(std::abs(res.r[k].y()));
  double p99 = 0;
  if (!a.empty()) {
    const size_t k = std::min(a.size() - 1, static_cast<size_t>(0.99 * a.size()));
    std::nth_element(a.begin(), a.begin() + k, a.end());
    p99 = a[k];
  }
  return std::max(4 * sigma, 1.1 * p99);
}

// Two cell maps side by side, each with its own scales (stated in its title): the final
// residual may be a hundredth of the nominal one.
void two_maps(const DiagnosisModel& m, const Residuals& left, const Residuals& right, const std::string& left_title,
              const std::string& right_title, const std::string& file) {
  const CameraModel& cam = m.recording().nominal.cam;
  const int nx = 16, ny = std::max(2, static_cast<int>(std::lround(16.0 * cam.height / cam.width)));
  const CellMeans a = cell_means(m, left, nx, ny), b = cell_means(m, right, nx, ny);
  const double cell = static_cast<double>(cam.width) / nx;
  const auto [sa, ra] = map_scales(a, cell);
  const auto [sb, rb] = map_scales(b, cell);
  open_page(file, 1800, 760);
  // Colour map 1: white (RMS 0) to dark red (the panel's largest cell RMS).
  PLFLT pos[2] = {0, 1}, red[2] = {1, 0.6}, green[2] = {1, 0}, blue[2] = {1, 0};
  plscmap1l(1, 2, pos, red, green, blue, nullptr);
  map_panel(m, a, sa, ra, 0.07, 0.47, left_title, map_scale_text(cell, sa, ra));
  map_panel(m, b, sb, rb, 0.57, 0.97, right_title, map_scale_text(cell, sb, rb));
}

}  // namespace

Residuals residuals_of(const DiagnosisModel& m, const ModelParams& p) {
  std::vector<int> all(m.size());
  for (int i = 0; i < m.size(); ++i) all[i] = i;
  Residuals r{m.residuals(p, all), {}};
  r.in = inliers(r.r);
  return r;
}

Figures figures_of(const DiagnosisModel& m, const Diagnosis& d) {
  const CameraModel& cam = m.recording().nominal.cam;
  Figures f{m, residuals_of(m, nominal_params(m.recording().nominal)), residuals_of(m, d.fitted), d.sigma_px, 0, 0, {}, {}, {}};
  f.range_before = residual_range(f.before, f.sigma);
  f.range_after = residual_range(f.after, f.sigma);
  double t0 = std::numeric_limits<double>::infinity();
  for (int i = 0; i < m.size(); ++i) t0 = std::min(t0, m.frame_time(i));
  for (int i = 0; i < m.size(); ++i) {
    const Eigen::Vector2d px = m.observed(i);
    f.row.push_back(px.y());
    f.radius.push_back(std::hypot(px.x() - cam.cx, px.y() - cam.cy));
    f.time.push_back(m.frame_time(i) - t0);
  }
  return f;
}

void residual_vs_figure(const Figures& f, const std::string& file, const std::vector<double>& x,
                        const std::string& what, const std::string& xlabel) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (double v : x) lo = std::min(lo, v), hi = std::max(hi, v);
  if (x.empty()) lo = 0;
  if (!(hi > lo)) hi = lo + 1;
  open_page(file, 1600, 1000);
  // Each panel has its own residual axis (the nominal one may be 100 times the final one).
  residual_panel(f, x, f.before, lo, hi, f.range_before, 0.55, 0.90, "Before: nominal model, residual against " + what,
                 xlabel, false);
  residual_panel(f, x, f.after, lo, hi, f.range_after, 0.10, 0.45, "After: final model (named effects fitted)", xlabel,
                 true);
  legend_notes(f.sigma);
  plend1();
}

void residual_map_figure(const Figures& f, const std::string& file) {
  two_maps(f.m, f.before, f.after, "Before: nominal model", "After: final model", file);
  plvpor(0, 1, 0, 1);
  plwind(0, 1, 0, 1);
  plcol0(kBlack);
  plschr(0, 0.9);
  plmtex("t", -1.4, 0.5, 0.5,
         "Residual per image cell (inliers; cells with >= 3 observations). Arrow: mean residual vector.");
  plmtex("t", -2.9, 0.5, 0.5, "Shade: residual RMS per coordinate, white = 0. Scales per panel, in its title.");
  plschr(0, 1.0);
  plend1();
}

// What one named effect removes: the residual without it minus the final residual, per
// observation (inliers of the final model).
Residuals removed_by(const Figures& f, const ModelParams& no_effect) {
  const Residuals w = residuals_of(f.m, no_effect);
  Residuals out{std::vector<Eigen::Vector2d>(w.r.size(), Eigen::Vector2d::Zero()), std::vector<bool>(w.r.size(), false)};
  for (size_t k = 0; k < w.r.size(); ++k)
    if (f.after.in[k] && w.r[k].allFinite()) out.r[k] = w.r[k] - f.after.r[k], out.in[k] = true;
  return out;
}

double rms_of(const Residuals& r) {
  double s = 0;
  int n = 0;
  for (size_t k = 0; k < r.r.size(); ++k)
    if (r.in[k]) s += r.r[k].squaredNorm(), ++n;
  return n > 0 ? std::sqrt(s / (2.0 * n)) : 0.0;
}

void effect_figure(const Figures& f, const Residuals& removed, const std::string& name, const std::string& file) {
  two_maps(f.m, removed, f.after, "What " + name + " removes", "Final residual", file);
  plend1();
}

// The remainder over time: each frame's mean residual (what moves a frame's observations
// together) and its RMS, against the noise the remainder test found.
void remainder_figure(const Figures& f, const Remainder& rem, const std::string& file) {
  std::map<double, std::pair<Eigen::Vector2d, std::pair<double, int>>> frames;  // time -> (sum, (sum sq, n))
  for (size_t k = 0; k < f.after.r.size(); ++k) {
    if (!f.after.in[k]) continue;
    auto [it, fresh] = frames.try_emplace(f.time[k], Eigen::Vector2d::Zero(), std::pair<double, int>{0.0, 0});
    auto& x = it->second;
    x.first += f.after.r[k], x.second.first += f.after.r[k].squaredNorm(), x.second.second += 1;
  }
  std::vector<PLFLT> t, mu, mv, rms;
  for (const auto& [time, x] : frames) {
    if (x.second.second < 3) continue;
    t.push_back(time);
    mu.push_back(x.first.x() / x.second.second), mv.push_back(x.first.y() / x.second.second);
    rms.push_back(std::sqrt(x.second.first / (2.0 * x.second.second)));
  }
  open_page(file, 1600, 1000);
  const double t1 = t.empty() ? 1 : std::max(t.back(), t.front() + 1e-6), t0 = t.empty() ? 0 : t.front();
  double mean_range = 4 * rem.expected_rms_px / 5, rms_top = 2 * std::max(rem.expected_rms_px, 1e-6);
  for (size_t k = 0; k < t.size(); ++k)
    mean_range = std::max(mean_range, 1.1 * std::max(std::abs(mu[k]), std::abs(mv[k]))), rms_top = std::max(rms_top, 1.1 * rms[k]);
  plvpor(0.08, 0.95, 0.55, 0.90);
  plwind(t0, t1, -mean_range, mean_range);
  plcol0(kLightGrey);
  plbox("g", 0, 0, "g", 0, 0);
  line(t, mu, kBlue, 2, 1);
  line(t, mv, kRed, 2, 1);
  plcol0(kBlack);
  plbox("bcst", 0, 0, "bcnstv", 0, 0);
  plmtex("l", 4.0, 0.5, 0.5, "frame mean (px)");
  plmtex("t", 0.8, 0.0, 0.0,
         ("Frame mean of the final residual: du (blue), dv (red); von Neumann " + format_number(rem.temporal_ratio, 3)).c_str());
  plvpor(0.08, 0.95, 0.10, 0.45);
  plwind(t0, t1, 0, rms_top);
  plcol0(kLightGrey);
  plbox("g", 0, 0, "g", 0, 0);
  std::vector<PLFLT> xs = {t0, t1}, expected = {rem.expected_rms_px, rem.expected_rms_px};
  line(xs, expected, kGrey, 2, 2);
  line(t, rms, kBlack, 2, 1);
  plcol0(kBlack);
  plbox("bcnst", 0, 0, "bcnstv", 0, 0);
  pllab("frame time since the first frame (s)", "", "");
  plmtex("l", 4.0, 0.5, 0.5, "frame RMS (px)");
  plmtex("t", 0.8, 0.0, 0.0,
         ("Final residual RMS per frame (black) against the noise alone, " + format_number(rem.expected_rms_px, 3) +
          " px (dashed)").c_str());
  plend1();
}

}  // namespace rsd::tools
