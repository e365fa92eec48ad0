// rsd-applicability: is the pinhole (global-shutter) model good enough for a rolling-shutter
// camera moving at a given speed past a scene at a given depth? Prints the paper's limit
// (Meingast, Geyer, Sastry 2005, Sec. "Domain of applicability") and the general, exact
// bound of dsp/applicability.hpp; --plot draws the paper's Figure 1 limit lines.
#include <CLI/CLI.hpp>
#include <plplot.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "dsp/applicability.hpp"

using namespace rsd::dsp;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr const char* kMarker = "\u25CF";  // filled circle, drawn as text (cairo fonts)

// ---------------------------------------------------------------- argument checking

// Strict number parsing: the whole string must be a finite number.
std::optional<double> parse_number(const std::string& s) {
  if (s.empty()) return std::nullopt;
  char* end = nullptr;
  const double x = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

std::optional<Eigen::Vector3d> parse_vec3(const std::string& s) {
  std::vector<std::string> parts;
  std::string cur;
  for (char c : s) {
    if (c == ',') {
      parts.push_back(cur);
      cur.clear();
    } else if (c != ' ') {
      cur += c;
    }
  }
  parts.push_back(cur);
  if (parts.size() != 3) return std::nullopt;
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    const auto x = parse_number(parts[i]);
    if (!x) return std::nullopt;
    v[i] = *x;
  }
  return v;
}

// CLI11 validators see the raw text; their message is prefixed with the option's name.
CLI::Validator positive(const std::string& unit) {
  return CLI::Validator(
      [unit](std::string& s) -> std::string {
        const auto x = parse_number(s);
        if (!x || !(*x > 0))
          return "expected a positive number (" + unit + "), got '" + s + "'";
        return {};
      },
      "> 0", "POSITIVE");
}
CLI::Validator finite_number(const std::string& unit) {
  return CLI::Validator(
      [unit](std::string& s) -> std::string {
        if (!parse_number(s)) return "expected a finite number (" + unit + "), got '" + s + "'";
        return {};
      },
      "", "FINITE");
}
CLI::Validator int_range(int lo, int hi) {
  return CLI::Validator(
      [lo, hi](std::string& s) -> std::string {
        const auto x = parse_number(s);
        if (!x || *x != std::floor(*x) || *x < lo || *x > hi)
          return "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                 "], got '" + s + "'";
        return {};
      },
      "", "INT");
}
CLI::Validator vec3(const std::string& what) {
  return CLI::Validator(
      [what](std::string& s) -> std::string {
        if (!parse_vec3(s))
          return "expected three comma-separated finite numbers " + what + ", got '" + s + "'";
        return {};
      },
      "X,Y,Z", "VEC3");
}

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// ---------------------------------------------------------------- formatting

std::string num(double x, int prec = 4) {
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  if (std::isnan(x)) return "nan";
  std::ostringstream o;
  o.precision(prec);
  o << x;
  return o.str();
}
std::string fixed(double x, int decimals) {
  if (!std::isfinite(x)) return num(x);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
  return buf;
}
std::string vec_str(const Eigen::Vector3d& v) {
  return "(" + num(v.x()) + ", " + num(v.y()) + ", " + num(v.z()) + ")";
}
// JSON has no infinity: null stands for "no depth suffices" / "not computed".
std::string jnum(double x) {
  if (!std::isfinite(x)) return "null";
  std::ostringstream o;
  o.precision(12);
  o << x;
  return o.str();
}
std::string jvec(const Eigen::Vector3d& v) {
  return "[" + jnum(v.x()) + ", " + jnum(v.y()) + ", " + jnum(v.z()) + "]";
}
std::string jstr(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o + "\"";
}
std::string depth_str(double z) {
  if (std::isinf(z)) return "none (no depth suffices)";
  if (z == 0) return "0 m (every depth suffices)";
  return num(z, 5) + " m";
}

// ---------------------------------------------------------------- plot

struct PlotInput {
  CameraModel cam;
  RowTiming user_timing;
  ApplicabilityOptions opt;
  std::optional<Eigen::Vector2d> user_point;  // (|v_y|, z)
};

// Exact min depth for v = (0, v_y, 0) moving along the readout (the worse sign).
double exact_line(const CameraModel& cam, const RowTiming& t, double vy,
                  const ApplicabilityOptions& opt) {
  Twist tw;
  tw.v = Eigen::Vector3d(0, t.r() > 0 ? vy : -vy, 0);
  return min_depth_for(cam, t, tw, opt);
}

void plot_limit_lines(const std::string& file, const PlotInput& in) {
  const bool svg = file.size() >= 4 && file.compare(file.size() - 4, 4, ".svg") == 0;
  struct Line {
    RowTiming timing;
    std::string label;
    int color;
  };
  std::vector<Line> lines;
  const double paper_fps[3] = {3.75, 7.5, 15.0};
  const int paper_col[3] = {2, 3, 4};  // blue, green, red, as in the paper's Figure 1
  bool user_is_paper = false;
  for (int i = 0; i < 3; ++i) {
    const RowTiming t = RowTiming::full_frame(in.cam.height, paper_fps[i], in.user_timing.readout);
    user_is_paper = user_is_paper || (std::abs(t.r() - in.user_timing.r()) < 1e-9 * std::abs(t.r()));
    lines.push_back({t, num(paper_fps[i]) + " fps", paper_col[i]});
  }
  if (!user_is_paper)
    lines.push_back({in.user_timing,
                     "yours (" + num(in.user_timing.frame_readout_s() * 1e3, 4) + " ms readout)",
                     6});

  double x_max = 3.0;
  if (in.user_point) x_max = std::max(x_max, 1.15 * in.user_point->x());
  double y_max = 0;
  for (const auto& l : lines)
    y_max = std::max(y_max, paper_min_depth(in.cam, l.timing, x_max, in.opt.threshold_px));
  if (in.user_point) y_max = std::max(y_max, 1.15 * in.user_point->y());
  y_max *= 1.05;

  // Paper: a straight line through the origin. Exact: computed at a few speeds (it is
  // linear in v_y too, since the correction depends on v_y / z only).
  constexpr int kPaperPts = 2, kExactPts = 7;
  std::vector<std::vector<PLFLT>> px(lines.size()), py(lines.size()), ex(lines.size()),
      ey(lines.size());
  for (size_t k = 0; k < lines.size(); ++k) {
    for (int i = 0; i < kPaperPts; ++i) {
      const double vy = x_max * i / (kPaperPts - 1);
      px[k].push_back(vy);
      py[k].push_back(paper_min_depth(in.cam, lines[k].timing, vy, in.opt.threshold_px));
    }
    ex[k].push_back(0);
    ey[k].push_back(0);
    for (int i = 1; i < kExactPts; ++i) {
      const double vy = x_max * i / (kExactPts - 1);
      // For v = (0, v_y, 0) the worst point is on the row read last, which every grid
      // holds, so a 33-column grid gives the same line as a finer one, faster.
      const double z = exact_line(in.cam, lines[k].timing, vy, grid_for(in.cam, 33, in.opt));
      if (std::isfinite(z)) {
        ex[k].push_back(vy);
        ey[k].push_back(z);
      }
    }
  }

  plsdev(svg ? "svgcairo" : "pngcairo");
  plsfnam(file.c_str());
  plspage(0, 0, 1600, 900, 0, 0);  // pixels (PNG) or points (SVG): the same layout
  // Colour map 0: white background, black ink, the paper's blue/green/red, grey grid.
  plscol0(0, 255, 255, 255);
  plscol0(1, 0, 0, 0);
  plscol0(2, 0, 70, 230);
  plscol0(3, 0, 150, 40);
  plscol0(4, 220, 20, 20);
  plscol0(5, 200, 200, 200);
  plscol0(6, 90, 90, 90);
  plscol0(7, 150, 0, 170);
  plinit();
  plfont(1);
  plschr(0, 1.0);
  pladv(0);
  // Titles over the whole width, then the plot on the left and the legend to its right.
  plvpor(0.02, 0.98, 0.12, 0.87);
  plwind(0, 1, 0, 1);
  plcol0(1);
  const std::string title =
      "Limit lines of the pinhole model, " + std::to_string(in.cam.width) + " x " +
      std::to_string(in.cam.height) + " px, f#dy#u = " + fixed(in.cam.fy, 1) + " px, N = " +
      num(in.opt.threshold_px) + " px";
  plschr(0, 1.05);
  plmtex("t", 3.0, 0.5, 0.5, title.c_str());
  plschr(0, 0.9);
  plmtex("t", 1.3, 0.5, 0.5,
         ("v = (0, v#dy#u, 0), #gw = 0, " + std::string(to_string(in.user_timing.readout)) +
          " readout filling the frame (r = " + std::to_string(in.cam.height) + " rows x fps)")
             .c_str());
  plschr(0, 1.0);
  plvpor(0.095, 0.60, 0.135, 0.87);
  plwind(0, x_max, 0, y_max);
  plcol0(5);
  plwidth(1);
  plbox("g", 0, 0, "g", 0, 0);
  plcol0(1);
  plbox("bcnst", 0, 0, "bcnstv", 0, 0);
  pllab("speed v#dy#u (m/s)", "", "");
  plmtex("l", 4.6, 0.5, 0.5, "depth z (m)");

  for (size_t k = 0; k < lines.size(); ++k) {
    plcol0(lines[k].color);
    plwidth(2.5);
    pllsty(1);
    plline(static_cast<PLINT>(px[k].size()), px[k].data(), py[k].data());
    pllsty(2);
    plline(static_cast<PLINT>(ex[k].size()), ex[k].data(), ey[k].data());
  }
  pllsty(1);
  plwidth(1);

  // Legend, two columns: per timing, paper (solid) and exact (dashed); then the user's point.
  std::vector<std::string> texts, symbols;
  std::vector<PLINT> opts, colors, styles, sym_numbers;
  std::vector<PLFLT> widths, sym_scales;
  auto entry = [&](const std::string& text, PLINT opt, int color, int style, const char* symbol) {
    texts.push_back(text);
    opts.push_back(opt);
    colors.push_back(color);
    styles.push_back(style);
    widths.push_back(2.5);
    sym_numbers.push_back(symbol[0] ? 1 : 0);
    sym_scales.push_back(1.0);
    symbols.push_back(symbol);
  };
  for (const auto& l : lines) {
    entry(l.label + ", paper", PL_LEGEND_LINE, l.color, 1, "");
    entry(l.label + ", exact", PL_LEGEND_LINE, l.color, 2, "");
  }
  if (in.user_point)
    entry("your (v#dy#u, z) = (" + num(in.user_point->x()) + " m/s, " + num(in.user_point->y()) +
              " m)",
          PL_LEGEND_SYMBOL, 7, 1, kMarker);
  std::vector<const char*> text_ptrs, sym_ptrs;
  for (const auto& t : texts) text_ptrs.push_back(t.c_str());
  for (const auto& t : symbols) sym_ptrs.push_back(t.c_str());
  std::vector<PLINT> text_colors(texts.size(), 1);
  const PLINT n = static_cast<PLINT>(texts.size());
  PLFLT lw = 0, lh = 0;
  plcol0(1);
  pllegend(&lw, &lh, PL_LEGEND_BACKGROUND | PL_LEGEND_BOUNDING_BOX,
           PL_POSITION_INSIDE | PL_POSITION_TOP | PL_POSITION_LEFT, 1.03, 0.0, 0.08, 0, 1, 1,
           n, 1, n, opts.data(), 0.7, 0.8, 2.0, 0.0, text_colors.data(),
           text_ptrs.data(), nullptr, nullptr, nullptr, nullptr, colors.data(), styles.data(),
           widths.data(), colors.data(), sym_scales.data(), sym_numbers.data(), sym_ptrs.data());
  // How to read it, below the legend.
  plcol0(6);
  plschr(0, 0.85);
  const char* notes[] = {"solid: paper, z = v#dy#u f#dy#u#u2#d / (N r)",
                         in.opt.reference == CorrectionReference::FrameStart
                             ? "dashed: exact bound (grid maximum)"
                             : "dashed: exact bound, middle-row reference",
                         "above a line: pinhole model sufficient",
                         "below a line: rolling-shutter model needed"};
  for (int i = 0; i < 4; ++i)
    plmtex("rv", 1.8, 1.0 - lh - 0.07 - 0.055 * i, 0.0, notes[i]);
  plschr(0, 1.0);

  if (in.user_point) {
    PLFLT ux = in.user_point->x(), uy = in.user_point->y();
    plcol0(7);
    plssym(0, 2.5);
    plpoin(1, &ux, &uy, 17);  // Hershey filled circle, centred on the point
    plcol0(1);
    plssym(0, 1.0);
    plpoin(1, &ux, &uy, 1);   // dot at the exact point
  }
  plend();
}

// ---------------------------------------------------------------- main

int run(int argc, char** argv) {
  CLI::App app{
      "rsd-applicability: is the pinhole (global-shutter) model good enough for a rolling-shutter\n"
      "camera, or is a rolling-shutter model needed? (Meingast, Geyer, Sastry 2005, Sec. 'Domain\n"
      "of applicability'.)\n\n"
      "Two answers are printed:\n"
      "  * the paper's limit line: the pinhole model is sufficient beyond the depth\n"
      "      z_min = |v_y| / (N s_alpha r_n) = |v_y| fy^2 / (N |r|)   [m]\n"
      "    with s_alpha = 1/fy (one pixel on the unit-focal image plane), r the row rate\n"
      "    (rows/s), r_n = r/fy, N = --threshold-px. It uses v_y only.\n"
      "  * the general (exact) bound: a fronto-parallel scene at depth z (m, in the camera\n"
      "    frame at frame start) is imaged with the exact rolling-shutter projection for\n"
      "    constant v and w (any direction); the largest image displacement from the pinhole\n"
      "    (perspective) image over a grid of pixels (corners included) is the bound. The\n"
      "    verdict is 'pinhole model sufficient' when it is below N pixels.\n\n"
      "Conventions (the paper's): camera axes x right, y down, z forward; v (m/s) and w\n"
      "(rad/s) are constant over the frame and give the motion of a static scene point in\n"
      "camera coordinates, dX_c/dt = w x X_c + v (v = dT/dt; the camera itself moves by -v).\n"
      "So v_y > 0 moves the image down, along a top-to-bottom readout (the worse sign).\n"
      "Pixels: u right, v down, origin at the centre of the top-left pixel.\n"
      "Timing defaults to the paper's: readout fills the frame, r = height * fps, d = 0.\n"
      "Vectors are three comma-separated numbers without spaces: --v 0,1.5,0 (or --v=-1,0,0).\n\n"
      "Example: rsd-applicability --v 0,1,0 --depth 10 --plot limit.png\n"
      "Exit status: 0 on success (whatever the verdict), 2 on bad arguments, 1 on other errors."};
  app.get_formatter()->column_width(34);

  int width = 640, height = 480;
  double fx = 0, fy = 0, hfov_deg = 40, cx = 0, cy = 0, fps = 15;
  double line_delay = 0, readout_time = 0, threshold = 1, depth = 0;
  int grid = 33;
  std::string readout = "top_to_bottom", reference = "frame_start", v_str = "0,0,0",
              w_str = "0,0,0", plot_file;
  bool json = false;

  app.add_option("--width", width, "Image width (pixels)")
      ->check(int_range(2, 100000))
      ->capture_default_str()
      ->group("Camera");
  app.add_option("--height", height, "Image height = number of rows read (pixels)")
      ->check(int_range(2, 100000))
      ->capture_default_str()
      ->group("Camera");
  auto* o_fx = app.add_option("--fx", fx,
                              "Focal length along x (pixels). Default: from --hfov-deg.\n"
                              "If only one of --fx/--fy is given, the other equals it")
                   ->check(positive("pixels"))
                   ->group("Camera");
  auto* o_fy = app.add_option("--fy", fy,
                              "Focal length along y (pixels); the paper's bound uses fy only")
                   ->check(positive("pixels"))
                   ->group("Camera");
  auto* o_hfov = app.add_option("--hfov-deg", hfov_deg,
                                "Horizontal field of view (degrees, 0..180); sets\n"
                                "fx = fy = (width/2) / tan(hfov/2) (40 deg: 879.2 px\n"
                                "at 640 px wide, the paper's Figure 1 camera)")
                     ->check(CLI::Validator(
                         [](std::string& s) -> std::string {
                           const auto x = parse_number(s);
                           if (!x || !(*x > 0 && *x < 180))
                             return "expected an angle in degrees strictly between 0 and 180, got '" +
                                    s + "'";
                           return {};
                         },
                         "(0, 180)", "DEGREES"))
                     ->capture_default_str()
                     ->group("Camera");
  o_hfov->excludes(o_fx)->excludes(o_fy);
  auto* o_cx = app.add_option("--cx", cx, "Principal point x (pixels). Default: (width-1)/2")
                   ->check(finite_number("pixels"))
                   ->group("Camera");
  auto* o_cy = app.add_option("--cy", cy, "Principal point y (pixels). Default: (height-1)/2")
                   ->check(finite_number("pixels"))
                   ->group("Camera");

  app.add_option("--fps", fps, "Frame rate (frames/s)")
      ->check(positive("frames per second"))
      ->capture_default_str()
      ->group("Timing");
  auto* o_ld = app.add_option("--line-delay", line_delay,
                              "Time between the starts of two consecutive rows (s).\n"
                              "Default 1/(height*fps): the readout fills the frame\n"
                              "(the paper's r = rows*fps, d = 0). Row rate |r| = 1/line-delay")
                   ->check(positive("seconds"))
                   ->group("Timing");
  auto* o_rt = app.add_option("--readout-time", readout_time,
                              "Time to read the whole frame (s) = height * line-delay.\n"
                              "Must not exceed 1/fps; the rest is the blanking d")
                   ->check(positive("seconds"))
                   ->group("Timing");
  o_ld->excludes(o_rt);
  app.add_option("--readout", readout, "Readout direction: top_to_bottom or bottom_to_top")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            Readout r;
            if (!parse_readout(s, r))
              return "expected top_to_bottom or bottom_to_top, got '" + s + "'";
            return {};
          },
          "top_to_bottom|bottom_to_top", "DIR"))
      ->capture_default_str()
      ->group("Timing");

  app.add_option("--v", v_str,
                             "Linear velocity vx,vy,vz (m/s) in camera axes\n"
                             "(x right, y down, z forward); the paper's bound uses vy")
                  ->check(vec3("vx,vy,vz in m/s"))
                  ->capture_default_str()
                  ->group("Motion");
  app.add_option("--w", w_str, "Angular velocity wx,wy,wz (rad/s) in camera axes")
      ->check(vec3("wx,wy,wz in rad/s"))
      ->capture_default_str()
      ->group("Motion");
  auto* o_depth = app.add_option("--depth", depth,
                                 "Depth z (m) of a fronto-parallel scene, along the optical\n"
                                 "axis. Without it, only the minimum depths are reported")
                      ->check(positive("metres"))
                      ->group("Motion");

  app.add_option("--threshold-px", threshold,
                 "N: largest rolling-shutter displacement (pixels) still\n"
                 "counted as noise")
      ->check(positive("pixels"))
      ->capture_default_str()
      ->group("Bound");
  app.add_option("--grid", grid,
                 "Grid columns over the image (rows in proportion, corners\n"
                 "included; 33 -> 33 x 25 points on 640 x 480). Cost grows\n"
                 "with the square: 257 takes seconds")
      ->check(int_range(2, 257))
      ->capture_default_str()
      ->group("Bound");
  app.add_option("--reference", reference,
                 "Pinhole image compared with: frame_start (the paper's\n"
                 "q(0), t = 0) or middle_row (perspective at the time the\n"
                 "middle row is read; about halves the bound)")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            CorrectionReference r;
            if (!parse_correction_reference(s.c_str(), r))
              return "expected frame_start or middle_row, got '" + s + "'";
            return {};
          },
          "frame_start|middle_row", "REF"))
      ->capture_default_str()
      ->group("Bound");

  app.add_flag("--json", json, "Print machine-readable JSON instead of text\n"
                               "(min_depth_m null: no depth suffices)")
      ->group("Output");
  app.add_option("--plot", plot_file,
                 "Draw the paper's limit lines z_min(v_y) for this camera at\n"
                 "3.75, 7.5, 15 fps (blue, green, red; solid = paper,\n"
                 "dashed = exact) to FILE.png or FILE.svg; marks\n"
                 "(|v_y|, depth) if --depth is given")
      ->check(CLI::Validator(
          [](std::string& s) -> std::string {
            auto ends = [&](const char* e) {
              const std::string ext(e);
              return s.size() > ext.size() && s.compare(s.size() - ext.size(), ext.size(), ext) == 0;
            };
            if (!ends(".png") && !ends(".svg"))
              return "file name must end in .png or .svg, got '" + s + "'";
            return {};
          },
          "FILE.png|FILE.svg", "FILE"))
      ->group("Output");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }

  // Camera.
  CameraModel cam = CameraModel::from_hfov(width, height, hfov_deg * kPi / 180);
  if (o_fx->count() || o_fy->count()) {
    cam.fx = o_fx->count() ? fx : fy;
    cam.fy = o_fy->count() ? fy : fx;
  }
  cam.cx = o_cx->count() ? cx : 0.5 * (width - 1);
  cam.cy = o_cy->count() ? cy : 0.5 * (height - 1);

  // Timing.
  RowTiming timing;
  timing.height = height;
  timing.frame_rate_hz = fps;
  parse_readout(readout, timing.readout);
  if (o_ld->count())
    timing.line_delay_s = line_delay;
  else if (o_rt->count())
    timing.line_delay_s = line_delay_from_frame_readout(readout_time, height);
  else
    timing.line_delay_s = 1.0 / (height * fps);
  if (!(timing.line_delay_s > 0) || !std::isfinite(timing.r()) || !std::isfinite(timing.v0())) {
    const std::string opt = o_ld->count() ? "--line-delay" : o_rt->count() ? "--readout-time" : "--fps";
    throw UsageError(opt + ": the line delay " + num(timing.line_delay_s) +
                     " s gives no finite row rate; use a realistic frame rate / readout time");
  }
  if (timing.frame_readout_s() > timing.frame_period_s() * (1 + 1e-9)) {
    const std::string opt = o_ld->count() ? "--line-delay" : "--readout-time";
    throw UsageError(opt + ": the readout time " + num(timing.frame_readout_s() * 1e3) +
                     " ms (height * line delay) exceeds the frame period 1/fps = " +
                     num(timing.frame_period_s() * 1e3) + " ms");
  }

  Twist tw;
  tw.v = *parse_vec3(v_str);
  tw.w = *parse_vec3(w_str);
  ApplicabilityOptions opt = grid_for(cam, grid);
  opt.threshold_px = threshold;
  parse_correction_reference(reference.c_str(), opt.reference);
  const bool have_depth = o_depth->count() > 0;

  if (!plot_file.empty()) {  // fail early and cleanly on an unwritable file
    std::ofstream probe(plot_file, std::ios::binary | std::ios::app);
    if (!probe) throw UsageError("--plot: cannot write '" + plot_file + "'");
  }

  // Bounds.
  const double z_paper = paper_min_depth(cam, timing, tw.v.y(), threshold);
  const double z_general = min_depth_for(cam, timing, tw, opt);
  std::optional<ApplicabilityResult> at;
  if (have_depth) at = correction_bound(cam, timing, tw, depth, opt);
  const bool only_vy = tw.v.x() == 0 && tw.v.z() == 0 && tw.w.isZero(0);

  std::string verdict;
  if (at) {
    verdict = at->pinhole_sufficient ? "pinhole model sufficient" : "rolling-shutter model needed";
  } else if (std::isinf(z_general)) {
    verdict = "rolling-shutter model needed at every depth";
  } else if (z_general == 0) {
    verdict = "pinhole model sufficient at every depth";
  } else {
    verdict = "pinhole model sufficient beyond " + num(z_general, 5) +
              " m; rolling-shutter model needed closer";
  }
  const double hfov_x = 2 * std::atan(0.5 * cam.width / cam.fx) * 180 / kPi;

  if (json) {
    std::ostringstream o;
    o << "{\n"
      << "  \"camera\": {\"width\": " << cam.width << ", \"height\": " << cam.height
      << ", \"fx\": " << jnum(cam.fx) << ", \"fy\": " << jnum(cam.fy) << ", \"cx\": " << jnum(cam.cx)
      << ", \"cy\": " << jnum(cam.cy) << ", \"hfov_deg\": " << jnum(hfov_x) << "},\n"
      << "  \"timing\": {\"readout\": " << jstr(std::string(to_string(timing.readout)))
      << ", \"fps\": " << jnum(fps) << ", \"line_delay_s\": " << jnum(timing.line_delay_s)
      << ", \"readout_time_s\": " << jnum(timing.frame_readout_s())
      << ", \"r_rows_per_s\": " << jnum(timing.r())
      << ", \"inter_frame_delay_s\": " << jnum(timing.inter_frame_delay_s()) << "},\n"
      << "  \"motion\": {\"v_m_per_s\": " << jvec(tw.v) << ", \"w_rad_per_s\": " << jvec(tw.w)
      << ", \"depth_m\": " << (have_depth ? jnum(depth) : "null") << "},\n"
      << "  \"threshold_px\": " << jnum(threshold) << ",\n"
      << "  \"paper_bound\": {\"min_depth_m\": " << jnum(z_paper) << ", \"uses_only_vy\": true"
      << ", \"pinhole_sufficient\": "
      << (have_depth ? (depth > z_paper ? "true" : "false") : "null") << "},\n"
      << "  \"general_bound\": {\"reference\": " << jstr(to_string(opt.reference))
      << ", \"grid\": [" << opt.grid_cols << ", " << opt.grid_rows << "]"
      << ", \"min_depth_m\": " << jnum(z_general) << ", \"no_depth_suffices\": "
      << (std::isinf(z_general) ? "true" : "false");
    if (at) {
      o << ", \"at_depth\": {\"max_correction_px\": " << jnum(at->max_correction_px)
        << ", \"worst_pixel\": [" << jnum(at->worst_pixel.x()) << ", " << jnum(at->worst_pixel.y())
        << "], \"worst_correction_px\": [" << jnum(at->worst_correction.x()) << ", "
        << jnum(at->worst_correction.y()) << "], \"mean_correction_px\": "
        << jnum(at->mean_correction_px) << ", \"grid_points\": " << at->grid_points
        << ", \"no_solution\": " << at->no_solution << ", \"pinhole_sufficient\": "
        << (at->pinhole_sufficient ? "true" : "false") << "}";
    } else {
      o << ", \"at_depth\": null";
    }
    o << "},\n"
      << "  \"verdict\": " << jstr(verdict) << "\n}\n";
    std::cout << o.str();
  } else {
    std::cout << "Camera     " << cam.width << " x " << cam.height << " px, fx = " << fixed(cam.fx, 2)
              << " px, fy = " << fixed(cam.fy, 2) << " px (hfov " << fixed(hfov_x, 2)
              << " deg), cx = " << fixed(cam.cx, 2) << ", cy = " << fixed(cam.cy, 2) << "\n"
              << "Timing     " << to_string(timing.readout) << ", " << num(fps) << " fps: line delay "
              << num(timing.line_delay_s * 1e6, 6) << " us, readout time "
              << num(timing.frame_readout_s() * 1e3, 6) << " ms, inter-frame delay d = "
              << num(timing.inter_frame_delay_s() * 1e3, 4) << " ms\n"
              << "           r = " << num(timing.r(), 6) << " rows/s (r/fy = "
              << num(timing.r() / cam.fy, 5) << " /s on the unit-focal image plane)\n"
              << "Motion     v = " << vec_str(tw.v) << " m/s, w = " << vec_str(tw.w) << " rad/s";
    if (have_depth) std::cout << ", depth z = " << num(depth, 6) << " m";
    std::cout << "\nThreshold  " << num(threshold) << " px\n\n";

    std::cout << "Paper's bound (v_y / (s_alpha r) < z, uses v_y only):\n"
              << "  min depth z_min = |v_y| fy^2 / (N |r|) = " << depth_str(z_paper) << "\n";
    if (have_depth)
      std::cout << "  at z = " << num(depth, 6) << " m: "
                << (depth > z_paper ? "pinhole model sufficient" : "rolling-shutter model needed")
                << "\n";
    if (!only_vy)
      std::cout << "  (note: your v_x, v_z or w are ignored by the paper's bound; trust the general one)\n";
    std::cout << "\nGeneral bound (exact rolling-shutter projection, " << opt.grid_cols << " x "
              << opt.grid_rows << " grid, reference " << to_string(opt.reference) << "):\n"
              << "  min depth for < " << num(threshold) << " px: " << depth_str(z_general) << "\n";
    if (at) {
      if (at->no_solution == at->grid_points)
        std::cout << "  at z = " << num(depth, 6) << " m: no grid point is captured at all";
      else
        std::cout << "  at z = " << num(depth, 6) << " m: max correction "
                  << num(at->max_correction_px, 5) << " px at pixel (" << num(at->worst_pixel.x(), 5)
                  << ", " << num(at->worst_pixel.y(), 5) << ") [du, dv = "
                  << num(at->worst_correction.x(), 4) << ", " << num(at->worst_correction.y(), 4)
                  << " px], mean " << num(at->mean_correction_px, 4) << " px";
      if (at->no_solution)
        std::cout << ";\n  " << at->no_solution << " of " << at->grid_points
                  << " grid points never captured (their image moves about as fast as\n  the readout, or faster)";
      std::cout << "\n";
    }
    std::cout << "\nVerdict: " << verdict;
    if (at && at->no_solution == at->grid_points)
      std::cout << " (no grid point is captured)";
    else if (at)
      std::cout << " (max correction " << num(at->max_correction_px, 4)
                << (at->pinhole_sufficient ? " px < " : " px >= ") << num(threshold) << " px"
                << (at->no_solution ? "; some points not captured" : "") << ")";
    std::cout << "\n";
  }

  if (!plot_file.empty()) {
    PlotInput in{cam, timing, opt, std::nullopt};
    if (have_depth) in.user_point = Eigen::Vector2d(std::abs(tw.v.y()), depth);
    plot_limit_lines(plot_file, in);
    if (!json) std::cout << "Plot written to " << plot_file << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const UsageError& e) {
    std::cerr << "rsd-applicability: error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "rsd-applicability: error: " << e.what() << "\n";
    return 1;
  }
}
