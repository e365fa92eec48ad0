#include "tools/report/limit_lines_plot.hpp"

#include <plplot.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tools/common/cli_util.hpp"
#include "tools/report/plot_page.hpp"

namespace rsd::tools {
namespace {

using namespace rsd::dsp;

// Colour map 0 entries, set in open_page.
enum Colour : PLINT {
  kWhite = 0,  // background
  kBlack = 1,  // ink
  kBlue = 2,   // 3.75 fps, 7.5 fps and 15 fps as in the paper's Figure 1
  kGreen = 3,
  kRed = 4,
  kLightGrey = 5,  // grid
  kGrey = 6,       // the user's own timing, and the notes
  kPurple = 7,     // the user's point
};

constexpr const char* kMarker = "\u25CF";  // filled circle, drawn as text (cairo fonts)
constexpr PLFLT kLineWidth = 2.5;

struct Line {
  RowTiming timing;
  std::string label;
  PLINT color;
};

struct Curve {
  std::vector<PLFLT> x, y;
};

// The paper's three frame rates, then the user's timing unless it is one of them.
std::vector<Line> timing_lines(const LimitLinesInput& in) {
  const double paper_fps[3] = {3.75, 7.5, 15.0};
  const PLINT paper_col[3] = {kBlue, kGreen, kRed};
  std::vector<Line> lines;
  bool user_is_paper = false;
  for (int i = 0; i < 3; ++i) {
    const RowTiming t = RowTiming::full_frame(in.cam.height, paper_fps[i], in.user_timing.readout);
    user_is_paper = user_is_paper || (std::abs(t.r() - in.user_timing.r()) < 1e-9 * std::abs(t.r()));
    lines.push_back({t, format_number(paper_fps[i]) + " fps", paper_col[i]});
  }
  if (!user_is_paper)
    lines.push_back({in.user_timing,
                     "yours (" + format_number(in.user_timing.frame_readout_s() * 1e3, 4) +
                         " ms readout)",
                     kGrey});
  return lines;
}

// Axis ranges: speeds up to 3 m/s (the paper's) and depths up to the steepest paper line,
// both stretched to show the user's point with a margin.
Eigen::Vector2d axis_maxima(const LimitLinesInput& in, const std::vector<Line>& lines) {
  double x_max = 3.0;
  if (in.user_point) x_max = std::max(x_max, 1.15 * in.user_point->x());
  double y_max = 0;
  for (const auto& l : lines)
    y_max = std::max(y_max, paper_min_depth(in.cam, l.timing, x_max, in.opt.threshold_px));
  if (in.user_point) y_max = std::max(y_max, 1.15 * in.user_point->y());
  return {x_max, y_max * 1.05};
}

// The paper's line is straight through the origin: its two ends suffice.
Curve paper_curve(const LimitLinesInput& in, const RowTiming& t, double x_max) {
  constexpr int kPoints = 2;
  Curve c;
  for (int i = 0; i < kPoints; ++i) {
    const double vy = x_max * i / (kPoints - 1);
    c.x.push_back(vy);
    c.y.push_back(paper_min_depth(in.cam, t, vy, in.opt.threshold_px));
  }
  return c;
}

// Exact min depth for v = (0, v_y, 0) moving along the readout (the worse sign).
double exact_min_depth(const CameraModel& cam, const RowTiming& t, double vy,
                       const ApplicabilityOptions& opt) {
  Twist tw;
  tw.v = Eigen::Vector3d(0, t.r() > 0 ? vy : -vy, 0);
  return min_depth_for(cam, t, tw, opt);
}

// The exact line is linear in v_y too (the correction depends on v_y / z only), so a few
// speeds show it; speeds no depth suffices for are left out.
Curve exact_curve(const LimitLinesInput& in, const RowTiming& t, double x_max) {
  constexpr int kPoints = 7;
  // For v = (0, v_y, 0) the worst point is on the row read last, which every grid
  // holds, so a 33-column grid gives the same line as a finer one, faster.
  const ApplicabilityOptions opt = grid_for(in.cam, 33, in.opt);
  Curve c{{0}, {0}};
  for (int i = 1; i < kPoints; ++i) {
    const double vy = x_max * i / (kPoints - 1);
    const double z = exact_min_depth(in.cam, t, vy, opt);
    if (std::isfinite(z)) {
      c.x.push_back(vy);
      c.y.push_back(z);
    }
  }
  return c;
}

void open_page(const std::string& file) {
  open_plot_page(file, 1600, 900,
                 {{kWhite, 255, 255, 255}, {kBlack, 0, 0, 0}, {kBlue, 0, 70, 230}, {kGreen, 0, 150, 40}, {kRed, 220, 20, 20},
                  {kLightGrey, 200, 200, 200}, {kGrey, 90, 90, 90}, {kPurple, 150, 0, 170}});
}

// Title and subtitle centred over the whole width (plot and legend).
void draw_titles(const LimitLinesInput& in) {
  plvpor(0.02, 0.98, 0.12, 0.87);
  plwind(0, 1, 0, 1);
  plcol0(kBlack);
  const std::string title =
      "Limit lines of the pinhole model, " + std::to_string(in.cam.width) + " x " +
      std::to_string(in.cam.height) + " px, f#dy#u = " + format_fixed(in.cam.fy, 1) +
      " px, N = " + format_number(in.opt.threshold_px) + " px";
  const std::string subtitle =
      "v = (0, v#dy#u, 0), #gw = 0, " + std::string(to_string(in.user_timing.readout)) +
      " readout filling the frame (r = " + std::to_string(in.cam.height) + " rows x fps)";
  plschr(0, 1.05);
  plmtex("t", 3.0, 0.5, 0.5, title.c_str());
  plschr(0, 0.9);
  plmtex("t", 1.3, 0.5, 0.5, subtitle.c_str());
  plschr(0, 1.0);
}

// The plot occupies the left part of the page; the legend goes to its right.
void draw_axes(const Eigen::Vector2d& maxima) {
  plvpor(0.095, 0.60, 0.135, 0.87);
  plwind(0, maxima.x(), 0, maxima.y());
  plcol0(kLightGrey);
  plwidth(1);
  plbox("g", 0, 0, "g", 0, 0);
  plcol0(kBlack);
  plbox("bcnst", 0, 0, "bcnstv", 0, 0);
  pllab("speed v#dy#u (m/s)", "", "");
  plmtex("l", 4.6, 0.5, 0.5, "depth z (m)");
}

void draw_curve(const Curve& c, PLINT color, PLINT style) {
  plcol0(color);
  plwidth(kLineWidth);
  pllsty(style);
  plline(static_cast<PLINT>(c.x.size()), c.x.data(), c.y.data());
}

// PLplot's pllegend takes parallel arrays, one element per entry.
struct Legend {
  std::vector<std::string> texts, symbols;
  std::vector<PLINT> opts, colors, styles, sym_numbers;
  std::vector<PLFLT> widths, sym_scales;

  void add(const std::string& text, PLINT opt, PLINT color, PLINT style, const char* symbol) {
    texts.push_back(text);
    opts.push_back(opt);
    colors.push_back(color);
    styles.push_back(style);
    widths.push_back(kLineWidth);
    sym_numbers.push_back(symbol[0] ? 1 : 0);
    sym_scales.push_back(1.0);
    symbols.push_back(symbol);
  }
};

// Per timing, paper (solid) and exact (dashed); then the user's point.
Legend legend_entries(const LimitLinesInput& in, const std::vector<Line>& lines) {
  Legend g;
  for (const auto& l : lines) {
    g.add(l.label + ", paper", PL_LEGEND_LINE, l.color, 1, "");
    g.add(l.label + ", exact", PL_LEGEND_LINE, l.color, 2, "");
  }
  if (in.user_point)
    g.add("your (v#dy#u, z) = (" + format_number(in.user_point->x()) + " m/s, " +
              format_number(in.user_point->y()) + " m)",
          PL_LEGEND_SYMBOL, kPurple, 1, kMarker);
  return g;
}

// Draws the legend right of the plot, top-aligned; returns its height (viewport units).
PLFLT draw_legend(const Legend& g) {
  std::vector<const char*> text_ptrs, sym_ptrs;
  for (const auto& t : g.texts) text_ptrs.push_back(t.c_str());
  for (const auto& t : g.symbols) sym_ptrs.push_back(t.c_str());
  std::vector<PLINT> text_colors(g.texts.size(), kBlack);
  const PLINT n = static_cast<PLINT>(g.texts.size());
  PLFLT lw = 0, lh = 0;
  plcol0(kBlack);
  pllegend(&lw, &lh, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
           PL_POSITION_INSIDE | PL_POSITION_TOP | PL_POSITION_LEFT, 1.03, 0.0, 0.08, 0, 1, 1,
           n, 1, n, g.opts.data(), 0.7, 0.8, 2.0, 0.0, text_colors.data(),
           text_ptrs.data(), nullptr, nullptr, nullptr, nullptr, g.colors.data(),
           g.styles.data(), g.widths.data(), g.colors.data(), g.sym_scales.data(),
           g.sym_numbers.data(), sym_ptrs.data());
  return lh;
}

// How to read the plot, below the legend (legend_height from draw_legend).
void draw_notes(const LimitLinesInput& in, PLFLT legend_height) {
  plcol0(kGrey);
  plschr(0, 0.85);
  const char* notes[] = {"solid: paper, z = v#dy#u f#dy#u#u2#d / (N r)",
                         in.opt.reference == CorrectionReference::FrameStart
                             ? "dashed: exact bound (grid maximum)"
                             : "dashed: exact bound, middle-row reference",
                         "above a line: pinhole model sufficient",
                         "below a line: rolling-shutter model needed"};
  for (int i = 0; i < 4; ++i)
    plmtex("rv", 1.8, 1.0 - legend_height - 0.07 - 0.055 * i, 0.0, notes[i]);
  plschr(0, 1.0);
}

void draw_user_point(const Eigen::Vector2d& p) {
  PLFLT ux = p.x(), uy = p.y();
  plcol0(kPurple);
  plssym(0, 2.5);
  plpoin(1, &ux, &uy, 17);  // Hershey filled circle, centred on the point
  plcol0(kBlack);
  plssym(0, 1.0);
  plpoin(1, &ux, &uy, 1);   // dot at the exact point
}

}  // namespace

void plot_limit_lines(const LimitLinesInput& in, const std::string& file) {
  // Everything is computed before PLplot starts, so a failure leaves no half-drawn page.
  const std::vector<Line> lines = timing_lines(in);
  const Eigen::Vector2d maxima = axis_maxima(in, lines);
  std::vector<Curve> paper, exact;
  for (const auto& l : lines) {
    paper.push_back(paper_curve(in, l.timing, maxima.x()));
    exact.push_back(exact_curve(in, l.timing, maxima.x()));
  }
  const Legend legend = legend_entries(in, lines);

  open_page(file);
  draw_titles(in);
  draw_axes(maxima);
  for (size_t k = 0; k < lines.size(); ++k) {
    draw_curve(paper[k], lines[k].color, 1);
    draw_curve(exact[k], lines[k].color, 2);
  }
  pllsty(1);
  plwidth(1);
  draw_notes(in, draw_legend(legend));
  if (in.user_point) draw_user_point(*in.user_point);
  plend();
}

}  // namespace rsd::tools
