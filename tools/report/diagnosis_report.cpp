#include "tools/report/diagnosis_report.hpp"

#include <plplot.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>

#include "tools/common/cli_util.hpp"
#include "tools/report/plot_page.hpp"

namespace rsd::tools {

using namespace rsd::dsp;
namespace fs = std::filesystem;

// ---------------------------------------------------------------- figures

namespace {

enum Colour : PLINT { kWhite = 0, kBlack, kLightBlue, kLightRed, kBlue, kRed, kLightGrey, kGrey };

// One model's residuals over all observations, with the inlier flags of its own robust scale.
struct Residuals {
  std::vector<Eigen::Vector2d> r;
  std::vector<bool> in;
};

struct Figures {
  const DiagnosisModel& m;
  Residuals before, after;
  double sigma;
  double range_before = 0, range_after = 0;       // residual axes: +-range px
  std::vector<double> row, radius, time;          // per observation
};

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

void residual_map_figure(const Figures& f, const std::string& file) {
  const CameraModel& cam = f.m.recording().nominal.cam;
  const int nx = 16, ny = std::max(2, static_cast<int>(std::lround(16.0 * cam.height / cam.width)));
  const CellMeans b = cell_means(f.m, f.before, nx, ny), a = cell_means(f.m, f.after, nx, ny);
  const double cell = static_cast<double>(cam.width) / nx;
  // Each panel has its own scales (stated in its title): the final model's residual may be
  // a hundredth of the nominal one's.
  const auto [sb, rb] = map_scales(b, cell);
  const auto [sa, ra] = map_scales(a, cell);
  open_page(file, 1800, 760);
  // Colour map 1: white (RMS 0) to dark red (the panel's largest cell RMS).
  PLFLT pos[2] = {0, 1}, red[2] = {1, 0.6}, green[2] = {1, 0}, blue[2] = {1, 0};
  plscmap1l(1, 2, pos, red, green, blue, nullptr);
  map_panel(f.m, b, sb, rb, 0.07, 0.47, "Before: nominal model", map_scale_text(cell, sb, rb));
  map_panel(f.m, a, sa, ra, 0.57, 0.97, "After: final model", map_scale_text(cell, sa, ra));
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

Residuals residuals_of(const DiagnosisModel& m, const ModelParams& p) {
  std::vector<int> all(m.size());
  for (int i = 0; i < m.size(); ++i) all[i] = i;
  Residuals r{m.residuals(p, all), {}};
  r.in = inliers(r.r);
  return r;
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

// ---------------------------------------------------------------- index.md

std::string verdict(const Diagnosis& d) {
  std::ostringstream o;
  if (d.effects.empty()) {
    o << "**Verdict: the recording agrees with its nominal model within its noise.** No named effect is "
         "supported by the data.";
  } else {
    o << "**Verdict: the nominal model does not fit; " << d.effects.size() << " named effect"
      << (d.effects.size() > 1 ? "s explain" : " explains") << " the difference:";
    for (size_t k = 0; k < d.effects.size(); ++k) o << (k ? ", " : " ") << "`" << d.effects[k].name << "`";
    o << ".**";
  }
  if (d.remainder.significant)
    o << " **Structure beyond noise remains that no named effect explains (see What remains).**";
  o << " Held-out RMS " << format_number(d.heldout_baseline_rms_px) << " px (nominal) -> "
    << format_number(d.heldout_final_rms_px) << " px (final); the residual sigma noise alone gives: "
    << format_number(d.sigma_px) << " px.\n";
  return o.str();
}

std::string nominal_value(const NominalModel& n, const std::string& name) {
  if (name == "frame_readout_s") return format_number(n.time.line_delay_s * n.cam.height, 6);
  if (name == "direction") return std::string(to_string(n.time.readout));
  if (const auto k = param_by_name(name)) return format_number(nominal_params(n)[*k], 6);
  return "";
}

std::string effects_table(const Diagnosis& d, const std::vector<ParamUncertainty>& u, const NominalModel& n) {
  std::ostringstream o;
  if (d.effects.empty()) return "None: the nominal model fits within the noise.\n";
  o << "| effect | parameter | fitted | 1-sigma | nominal |\n| --- | --- | --- | --- | --- |\n";
  for (const ParamUncertainty& p : u)
    o << "| `" << p.effect << "` | `" << p.param << "` | " << (p.text.empty() ? format_number(p.value, 6) : p.text)
      << " | " << (p.sigma ? format_number(*p.sigma, 3) : std::string("-")) << " | " << nominal_value(n, p.param)
      << " |\n";
  o << "\n| effect (order selected) | explains | fitting-set RMS with it (px) | BIC drop | held-out chi-square drop |\n"
       "| --- | --- | --- | --- | --- |\n";
  for (const NamedEffect& e : d.effects)
    o << "| `" << e.name << "` | " << e.explains << " | " << format_number(e.rms_px) << " | "
      << format_number(e.bic_drop) << " | " << format_number(e.heldout_drop) << " |\n";
  return o.str();
}

std::string remainder_section(const Remainder& r) {
  std::ostringstream o;
  o << "## What remains\n\n" << (r.significant ? "**Significant: physics the effect table does not hold.** " : "")
    << r.summary << "\n\n"
    << "| test | statistic | z | structured RMS (px) |\n| --- | --- | --- | --- |\n"
    << "| across each frame: scatter about the frame mean over nearest-neighbour differences (1 = noise) | "
    << format_number(r.spatial_ratio, 3) << " | " << format_number(r.spatial_z, 3) << " | "
    << format_number(r.spatial_rms_px, 3) << " |\n"
    << "| from frame to frame: von Neumann ratio of the frame means (1 = independent frames) | "
    << format_number(r.temporal_ratio, 3) << " | " << format_number(r.temporal_z, 3) << " | "
    << format_number(r.temporal_rms_px, 3) << " |\n\n"
    << "Structure is called significant when a test is clear (z above 4) and material (its variance at least a "
       "fifth of the noise's).\n";
  if (!r.located.empty()) {
    o << "\n| where the remainder lives | strength | detail |\n| --- | --- | --- |\n";
    for (const Located& l : r.located)
      o << "| `" << l.signal << "` | " << format_number(l.strength, 3) << " | " << l.detail << " |\n";
  }
  return o.str();
}

std::string index_markdown(const ReportInput& in, const std::vector<ParamUncertainty>& u) {
  const Diagnosis& d = *in.diagnosis;
  const NominalModel& n = in.model->recording().nominal;
  std::ostringstream o;
  o << "# Diagnosis of `" << in.recording_dir << "`\n\n" << verdict(d) << "\n";
  o << "| residual RMS (px, per coordinate, inliers) | nominal model | final model |\n| --- | --- | --- |\n"
    << "| held out: " << d.heldout_observations << " observations of every " << in.heldout_every
    << "th frame, not used by the fit | " << format_number(d.heldout_baseline_rms_px) << " | "
    << format_number(d.heldout_final_rms_px) << " |\n"
    << "| all " << d.baseline.observations << " observations | " << format_number(d.baseline.rms_px) << " | "
    << format_number(d.final_rms_px) << " |\n\n"
    << "Outliers of the nominal model (beyond " << kOutlierSigmas << " robust sigmas, or no prediction): "
    << d.baseline.outliers << ". Diagnosis took " << format_number(in.seconds, 3) << " s.\n\n";
  o << "## Named effects\n\n" << effects_table(d, u, n) << "\n";
  if (!d.candidates.empty()) {
    o << "Effects considered for this recording:";
    for (size_t k = 0; k < d.candidates.size(); ++k) o << (k ? ", " : " ") << "`" << d.candidates[k] << "`";
    o << " (an effect is named when the evidence for it, BIC, is very strong).\n\n";
  }
  o << "Uncertainties: 1-sigma from the fit's numeric Jacobian J over the fitting-set inliers, all named "
       "effects' parameters free together (correlations widen them): the larger of the classic s^2 (J^T J)^-1 "
       "(s the per-coordinate RMS of those residuals) and the sandwich estimate clustered by frame, which also "
       "sees errors a frame's observations share (gyro noise, stamp jitter). They hold if the named effects are "
       "the whole story.\n\n";
  o << "## Where the residual lives (nominal model)\n\n";
  if (d.located.empty()) o << "No structured residual (no signal explains 5% of it).\n";
  else o << "| signal | strength | detail |\n| --- | --- | --- |\n";
  for (const Located& l : d.located)
    o << "| `" << l.signal << "` | " << format_number(l.strength, 3) << " | " << l.detail << " |\n";
  o << "\n" << remainder_section(d.remainder);
  o << "\n## Figures\n\nTop panels: the nominal model; bottom: the final one. Pixel positions are "
    << (in.model->recording().kind == ObservationKind::Matches ? "frame_b's (the predicted end of each match)"
                                                               : "the observed landmarks'")
    << "; outliers are left out.\n\n"
    << "![Residual against image row](residual-vs-row.png)\n\n"
    << "![Residual against radius](residual-vs-radius.png)\n\n"
    << "![Residual against time](residual-vs-time.png)\n\n"
    << "![Residual map](residual-map.png)\n";
  return o.str();
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
  if (!f) throw std::runtime_error(path.string() + ": cannot write");
}

}  // namespace

std::vector<std::string> write_report(const std::string& report_dir, const ReportInput& in) {
  const DiagnosisModel& m = *in.model;
  const Diagnosis& d = *in.diagnosis;
  const fs::path dir(report_dir);
  fs::create_directories(dir);
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
  std::vector<std::string> files;
  auto png = [&](const char* name) { return files.emplace_back((dir / name).string()); };
  residual_vs_figure(f, png("residual-vs-row.png"), f.row, "image row", "image row v (px)");
  residual_vs_figure(f, png("residual-vs-radius.png"), f.radius, "radius", "distance from the principal point (px)");
  residual_vs_figure(f, png("residual-vs-time.png"), f.time, "time", "frame time since the first frame (s)");
  residual_map_figure(f, png("residual-map.png"));
  const std::vector<ParamUncertainty>& u = d.uncertainties;
  write_text(dir / "index.md", index_markdown(in, u));
  files.push_back((dir / "index.md").string());
  return files;
}

}  // namespace rsd::tools
