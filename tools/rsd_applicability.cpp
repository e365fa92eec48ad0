// rsd-applicability: is the pinhole (global-shutter) model good enough for a rolling-shutter
// camera moving at a given speed past a scene at a given depth? Prints the paper's limit
// (Meingast, Geyer, Sastry 2005, Sec. "Domain of applicability") and the general, exact
// bound of dsp/analysis/applicability.hpp; --plot draws the paper's Figure 1 limit lines.
#include <CLI/CLI.hpp>

#include <cmath>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>

#include "tools/common/cli_util.hpp"
#include "dsp/analysis/applicability.hpp"
#include "tools/report/limit_lines_plot.hpp"

using namespace rsd::dsp;
using namespace rsd::tools;

namespace {

constexpr double kPi = 3.14159265358979323846;

// ---------------------------------------------------------------- options

constexpr const char* kDescription =
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
    "Exit status: 0 on success (whatever the verdict), 2 on bad arguments, 1 on other errors.";

// The command line as given. Options without a fixed default (derived from others when
// absent) have a *_given flag; their value is meaningless without it.
struct Options {
  int width = 640, height = 480;
  double fx = 0, fy = 0, hfov_deg = 40, cx = 0, cy = 0;
  bool fx_given = false, fy_given = false, cx_given = false, cy_given = false;
  double fps = 15, line_delay = 0, readout_time = 0;
  bool line_delay_given = false, readout_time_given = false;
  std::string readout = "top_to_bottom";
  std::string v = "0,0,0", w = "0,0,0";  // validated by vec3(), parsed later
  double depth = 0;
  bool depth_given = false;
  double threshold = 1;
  int grid = 33;
  std::string reference = "frame_start";
  bool json = false;
  std::string plot_file;  // empty: no plot
};

void add_camera_options(CLI::App& app, Options& o) {
  app.add_option("--width", o.width, "Image width (pixels)")
      ->check(int_range(2, 100000))->capture_default_str()->group("Camera");
  app.add_option("--height", o.height, "Image height = number of rows read (pixels)")
      ->check(int_range(2, 100000))->capture_default_str()->group("Camera");
  auto* fx = app.add_option("--fx", o.fx,
                            "Focal length along x (pixels). Default: from --hfov-deg.\n"
                            "If only one of --fx/--fy is given, the other equals it")
                 ->check(positive("pixels"))->group("Camera");
  auto* fy = app.add_option("--fy", o.fy,
                            "Focal length along y (pixels); the paper's bound uses fy only")
                 ->check(positive("pixels"))->group("Camera");
  app.add_option("--hfov-deg", o.hfov_deg,
                 "Horizontal field of view (degrees, 0..180); sets\n"
                 "fx = fy = (width/2) / tan(hfov/2) (40 deg: 879.2 px\n"
                 "at 640 px wide, the paper's Figure 1 camera)")
      ->check(open_interval(0, 180, "an angle in degrees", "DEGREES"))
      ->capture_default_str()->group("Camera")
      ->excludes(fx)->excludes(fy);
  app.add_option("--cx", o.cx, "Principal point x (pixels). Default: (width-1)/2")
      ->check(finite_number("pixels"))->group("Camera");
  app.add_option("--cy", o.cy, "Principal point y (pixels). Default: (height-1)/2")
      ->check(finite_number("pixels"))->group("Camera");
}

void add_timing_options(CLI::App& app, Options& o) {
  app.add_option("--fps", o.fps, "Frame rate (frames/s)")
      ->check(positive("frames per second"))->capture_default_str()->group("Timing");
  auto* ld = app.add_option("--line-delay", o.line_delay,
                            "Time between the starts of two consecutive rows (s).\n"
                            "Default 1/(height*fps): the readout fills the frame\n"
                            "(the paper's r = rows*fps, d = 0). Row rate |r| = 1/line-delay")
                 ->check(positive("seconds"))->group("Timing");
  auto* rt = app.add_option("--readout-time", o.readout_time,
                            "Time to read the whole frame (s) = height * line-delay.\n"
                            "Must not exceed 1/fps; the rest is the blanking d")
                 ->check(positive("seconds"))->group("Timing");
  ld->excludes(rt);
  app.add_option("--readout", o.readout, "Readout direction: top_to_bottom or bottom_to_top")
      ->check(text_check(
          [](const std::string& s) {
            Readout r;
            return parse_readout(s, r);
          },
          "expected top_to_bottom or bottom_to_top", "top_to_bottom|bottom_to_top", "DIR"))
      ->capture_default_str()->group("Timing");
}

void add_motion_options(CLI::App& app, Options& o) {
  app.add_option("--v", o.v,
                 "Linear velocity vx,vy,vz (m/s) in camera axes\n"
                 "(x right, y down, z forward); the paper's bound uses vy")
      ->check(vec3("vx,vy,vz in m/s"))->capture_default_str()->group("Motion");
  app.add_option("--w", o.w, "Angular velocity wx,wy,wz (rad/s) in camera axes")
      ->check(vec3("wx,wy,wz in rad/s"))->capture_default_str()->group("Motion");
  app.add_option("--depth", o.depth,
                 "Depth z (m) of a fronto-parallel scene, along the optical\n"
                 "axis. Without it, only the minimum depths are reported")
      ->check(positive("metres"))->group("Motion");
}

void add_bound_options(CLI::App& app, Options& o) {
  app.add_option("--threshold-px", o.threshold,
                 "N: largest rolling-shutter displacement (pixels) still\n"
                 "counted as noise")
      ->check(positive("pixels"))->capture_default_str()->group("Bound");
  app.add_option("--grid", o.grid,
                 "Grid columns over the image (rows in proportion, corners\n"
                 "included; 33 -> 33 x 25 points on 640 x 480). Cost grows\n"
                 "with the square: 257 takes seconds")
      ->check(int_range(2, 257))->capture_default_str()->group("Bound");
  app.add_option("--reference", o.reference,
                 "Pinhole image compared with: frame_start (the paper's\n"
                 "q(0), t = 0) or middle_row (perspective at the time the\n"
                 "middle row is read; about halves the bound)")
      ->check(text_check(
          [](const std::string& s) {
            CorrectionReference r;
            return parse_correction_reference(s.c_str(), r);
          },
          "expected frame_start or middle_row", "frame_start|middle_row", "REF"))
      ->capture_default_str()->group("Bound");
}

void add_output_options(CLI::App& app, Options& o) {
  app.add_flag("--json", o.json,
               "Print machine-readable JSON instead of text\n"
               "(min_depth_m null: no depth suffices)")
      ->group("Output");
  app.add_option("--plot", o.plot_file,
                 "Draw the paper's limit lines z_min(v_y) for this camera at\n"
                 "3.75, 7.5, 15 fps (blue, green, red; solid = paper,\n"
                 "dashed = exact) to FILE.png or FILE.svg; marks\n"
                 "(|v_y|, depth) if --depth is given")
      ->check(file_extension({".png", ".svg"}))->group("Output");
}

// Fills `o` from the command line. Returns the exit status when the tool should stop
// (after --help or on a parse error), nullopt to go on.
std::optional<int> parse_options(int argc, char** argv, Options& o) {
  CLI::App app{kDescription};
  app.get_formatter()->column_width(34);
  // The order of the add_* calls is the order of the groups in --help.
  add_camera_options(app, o);
  add_timing_options(app, o);
  add_motion_options(app, o);
  add_bound_options(app, o);
  add_output_options(app, o);
  if (const auto rc = parse_command_line(app, argc, argv)) return rc;
  o.fx_given = app.count("--fx") > 0;
  o.fy_given = app.count("--fy") > 0;
  o.cx_given = app.count("--cx") > 0;
  o.cy_given = app.count("--cy") > 0;
  o.line_delay_given = app.count("--line-delay") > 0;
  o.readout_time_given = app.count("--readout-time") > 0;
  o.depth_given = app.count("--depth") > 0;
  return std::nullopt;
}

// ---------------------------------------------------------------- the problem

// The camera, its timing, the motion and the bound's settings, from the options.
struct Problem {
  CameraModel cam;
  RowTiming timing;
  Twist tw;
  ApplicabilityOptions opt;
  std::optional<double> depth;  // metres; without it only minimum depths are computed
};

CameraModel make_camera(const Options& o) {
  CameraModel cam = CameraModel::from_hfov(o.width, o.height, o.hfov_deg * kPi / 180);
  if (o.fx_given || o.fy_given) {  // one focal length given stands for both
    cam.fx = o.fx_given ? o.fx : o.fy;
    cam.fy = o.fy_given ? o.fy : o.fx;
  }
  cam.cx = o.cx_given ? o.cx : 0.5 * (o.width - 1);
  cam.cy = o.cy_given ? o.cy : 0.5 * (o.height - 1);
  return cam;
}

// Each option is valid alone (CLI11 checked it), but together they may give no usable
// timing; the error names the option that decided the line delay.
void check_timing(const RowTiming& t, const Options& o) {
  if (!(t.line_delay_s > 0) || !std::isfinite(t.r()) || !std::isfinite(t.v0())) {
    const std::string opt = o.line_delay_given     ? "--line-delay"
                            : o.readout_time_given ? "--readout-time"
                                                   : "--fps";
    throw UsageError(opt + ": the line delay " + format_number(t.line_delay_s) +
                     " s gives no finite row rate; use a realistic frame rate / readout time");
  }
  if (t.frame_readout_s() > t.frame_period_s() * (1 + 1e-9)) {  // slack for rounding
    const std::string opt = o.line_delay_given ? "--line-delay" : "--readout-time";
    throw UsageError(opt + ": the readout time " + format_number(t.frame_readout_s() * 1e3) +
                     " ms (height * line delay) exceeds the frame period 1/fps = " +
                     format_number(t.frame_period_s() * 1e3) + " ms");
  }
}

RowTiming make_timing(const Options& o) {
  RowTiming t;
  t.height = o.height;
  t.frame_rate_hz = o.fps;
  parse_readout(o.readout, t.readout);
  if (o.line_delay_given)
    t.line_delay_s = o.line_delay;
  else if (o.readout_time_given)
    t.line_delay_s = line_delay_from_frame_readout(o.readout_time, o.height);
  else
    t.line_delay_s = 1.0 / (o.height * o.fps);  // the paper's: the readout fills the frame
  check_timing(t, o);
  return t;
}

Problem make_problem(const Options& o) {
  Problem p;
  p.cam = make_camera(o);
  p.timing = make_timing(o);
  p.tw.v = *parse_vec3(o.v);  // the validators guarantee these parse
  p.tw.w = *parse_vec3(o.w);
  p.opt = grid_for(p.cam, o.grid);
  p.opt.threshold_px = o.threshold;
  parse_correction_reference(o.reference.c_str(), p.opt.reference);
  if (o.depth_given) p.depth = o.depth;
  return p;
}

// ---------------------------------------------------------------- the bounds

struct Bounds {
  double z_paper = 0;    // the paper's minimum depth (m)
  double z_general = 0;  // the exact minimum depth (m); inf: none suffices
  std::optional<ApplicabilityResult> at;  // the exact bound at --depth, if given
  std::string verdict;
};

std::string verdict_for(const Bounds& b) {
  if (b.at)
    return b.at->pinhole_sufficient ? "pinhole model sufficient" : "rolling-shutter model needed";
  if (std::isinf(b.z_general)) return "rolling-shutter model needed at every depth";
  if (b.z_general == 0) return "pinhole model sufficient at every depth";
  return "pinhole model sufficient beyond " + format_number(b.z_general, 5) +
         " m; rolling-shutter model needed closer";
}

Bounds compute_bounds(const Problem& p) {
  Bounds b;
  b.z_paper = paper_min_depth(p.cam, p.timing, p.tw.v.y(), p.opt.threshold_px);
  b.z_general = min_depth_for(p.cam, p.timing, p.tw, p.opt);
  if (p.depth) b.at = correction_bound(p.cam, p.timing, p.tw, *p.depth, p.opt);
  b.verdict = verdict_for(b);
  return b;
}

double hfov_x_deg(const CameraModel& cam) {
  return 2 * std::atan(0.5 * cam.width / cam.fx) * 180 / kPi;
}

// ---------------------------------------------------------------- text output

std::string depth_str(double z) {
  if (std::isinf(z)) return "none (no depth suffices)";
  if (z == 0) return "0 m (every depth suffices)";
  return format_number(z, 5) + " m";
}

void print_setup(const Problem& p) {
  const CameraModel& c = p.cam;
  const RowTiming& t = p.timing;
  std::cout << "Camera     " << c.width << " x " << c.height << " px, fx = "
            << format_fixed(c.fx, 2) << " px, fy = " << format_fixed(c.fy, 2) << " px (hfov "
            << format_fixed(hfov_x_deg(c), 2) << " deg), cx = " << format_fixed(c.cx, 2)
            << ", cy = " << format_fixed(c.cy, 2) << "\n"
            << "Timing     " << to_string(t.readout) << ", " << format_number(t.frame_rate_hz)
            << " fps: line delay " << format_number(t.line_delay_s * 1e6, 6)
            << " us, readout time " << format_number(t.frame_readout_s() * 1e3, 6)
            << " ms, inter-frame delay d = " << format_number(t.inter_frame_delay_s() * 1e3, 4)
            << " ms\n"
            << "           r = " << format_number(t.r(), 6) << " rows/s (r/fy = "
            << format_number(t.r() / c.fy, 5) << " /s on the unit-focal image plane)\n"
            << "Motion     v = " << format_vec3(p.tw.v) << " m/s, w = " << format_vec3(p.tw.w)
            << " rad/s";
  if (p.depth) std::cout << ", depth z = " << format_number(*p.depth, 6) << " m";
  std::cout << "\nThreshold  " << format_number(p.opt.threshold_px) << " px\n\n";
}

void print_paper_bound(const Problem& p, const Bounds& b) {
  std::cout << "Paper's bound (v_y / (s_alpha r) < z, uses v_y only):\n"
            << "  min depth z_min = |v_y| fy^2 / (N |r|) = " << depth_str(b.z_paper) << "\n";
  if (p.depth)
    std::cout << "  at z = " << format_number(*p.depth, 6) << " m: "
              << (*p.depth > b.z_paper ? "pinhole model sufficient"
                                       : "rolling-shutter model needed")
              << "\n";
  const bool only_vy = p.tw.v.x() == 0 && p.tw.v.z() == 0 && p.tw.w.isZero(0);
  if (!only_vy)
    std::cout << "  (note: your v_x, v_z or w are ignored by the paper's bound; trust the "
                 "general one)\n";
}

void print_at_depth(double depth, const ApplicabilityResult& at) {
  std::cout << "  at z = " << format_number(depth, 6) << " m: ";
  if (at.no_solution == at.grid_points)
    std::cout << "no grid point is captured at all";
  else
    std::cout << "max correction " << format_number(at.max_correction_px, 5) << " px at pixel ("
              << format_number(at.worst_pixel.x(), 5) << ", "
              << format_number(at.worst_pixel.y(), 5) << ") [du, dv = "
              << format_number(at.worst_correction.x(), 4) << ", "
              << format_number(at.worst_correction.y(), 4) << " px], mean "
              << format_number(at.mean_correction_px, 4) << " px";
  if (at.no_solution)
    std::cout << ";\n  " << at.no_solution << " of " << at.grid_points
              << " grid points never captured (their image moves about as fast as\n  the "
                 "readout, or faster)";
  std::cout << "\n";
}

void print_general_bound(const Problem& p, const Bounds& b) {
  std::cout << "\nGeneral bound (exact rolling-shutter projection, " << p.opt.grid_cols << " x "
            << p.opt.grid_rows << " grid, reference " << to_string(p.opt.reference) << "):\n"
            << "  min depth for < " << format_number(p.opt.threshold_px)
            << " px: " << depth_str(b.z_general) << "\n";
  if (b.at) print_at_depth(*p.depth, *b.at);
}

void print_verdict(const Problem& p, const Bounds& b) {
  std::cout << "\nVerdict: " << b.verdict;
  if (b.at && b.at->no_solution == b.at->grid_points)
    std::cout << " (no grid point is captured)";
  else if (b.at)
    std::cout << " (max correction " << format_number(b.at->max_correction_px, 4)
              << (b.at->pinhole_sufficient ? " px < " : " px >= ")
              << format_number(p.opt.threshold_px) << " px"
              << (b.at->no_solution ? "; some points not captured" : "") << ")";
  std::cout << "\n";
}

void print_text(const Problem& p, const Bounds& b) {
  print_setup(p);
  print_paper_bound(p, b);
  print_general_bound(p, b);
  print_verdict(p, b);
}

// ---------------------------------------------------------------- JSON output

// The "camera", "timing" and "motion" members, one line each.
void json_setup(std::ostream& o, const Problem& p) {
  const CameraModel& c = p.cam;
  const RowTiming& t = p.timing;
  o << "  \"camera\": {\"width\": " << c.width << ", \"height\": " << c.height
    << ", \"fx\": " << json_number(c.fx) << ", \"fy\": " << json_number(c.fy)
    << ", \"cx\": " << json_number(c.cx) << ", \"cy\": " << json_number(c.cy)
    << ", \"hfov_deg\": " << json_number(hfov_x_deg(c)) << "},\n"
    << "  \"timing\": {\"readout\": " << json_string(std::string(to_string(t.readout)))
    << ", \"fps\": " << json_number(t.frame_rate_hz)
    << ", \"line_delay_s\": " << json_number(t.line_delay_s)
    << ", \"readout_time_s\": " << json_number(t.frame_readout_s())
    << ", \"r_rows_per_s\": " << json_number(t.r())
    << ", \"inter_frame_delay_s\": " << json_number(t.inter_frame_delay_s()) << "},\n"
    << "  \"motion\": {\"v_m_per_s\": " << json_vec3(p.tw.v)
    << ", \"w_rad_per_s\": " << json_vec3(p.tw.w)
    << ", \"depth_m\": " << (p.depth ? json_number(*p.depth) : "null") << "},\n";
}

// The "at_depth" object (without its key).
std::string json_at_depth(const ApplicabilityResult& at) {
  std::ostringstream o;
  o << "{\"max_correction_px\": " << json_number(at.max_correction_px)
    << ", \"worst_pixel\": [" << json_number(at.worst_pixel.x()) << ", "
    << json_number(at.worst_pixel.y()) << "], \"worst_correction_px\": ["
    << json_number(at.worst_correction.x()) << ", " << json_number(at.worst_correction.y())
    << "], \"mean_correction_px\": " << json_number(at.mean_correction_px)
    << ", \"grid_points\": " << at.grid_points << ", \"no_solution\": " << at.no_solution
    << ", \"pinhole_sufficient\": " << (at.pinhole_sufficient ? "true" : "false") << "}";
  return o.str();
}

// The "threshold_px", "paper_bound" and "general_bound" members.
void json_bounds(std::ostream& o, const Problem& p, const Bounds& b) {
  const char* paper_ok = p.depth ? (*p.depth > b.z_paper ? "true" : "false") : "null";
  o << "  \"threshold_px\": " << json_number(p.opt.threshold_px) << ",\n"
    << "  \"paper_bound\": {\"min_depth_m\": " << json_number(b.z_paper)
    << ", \"uses_only_vy\": true, \"pinhole_sufficient\": " << paper_ok << "},\n"
    << "  \"general_bound\": {\"reference\": " << json_string(to_string(p.opt.reference))
    << ", \"grid\": [" << p.opt.grid_cols << ", " << p.opt.grid_rows << "]"
    << ", \"min_depth_m\": " << json_number(b.z_general)
    << ", \"no_depth_suffices\": " << (std::isinf(b.z_general) ? "true" : "false")
    << ", \"at_depth\": " << (b.at ? json_at_depth(*b.at) : "null") << "},\n";
}

void print_json(const Problem& p, const Bounds& b) {
  std::ostringstream o;
  o << "{\n";
  json_setup(o, p);
  json_bounds(o, p, b);
  o << "  \"verdict\": " << json_string(b.verdict) << "\n}\n";
  std::cout << o.str();
}

// ---------------------------------------------------------------- main

void plot(const Problem& p, const std::string& file) {
  LimitLinesInput in{p.cam, p.timing, p.opt, std::nullopt};
  if (p.depth) in.user_point = Eigen::Vector2d(std::abs(p.tw.v.y()), *p.depth);
  plot_limit_lines(in, file);
}

int run(int argc, char** argv) {
  Options o;
  if (const auto rc = parse_options(argc, argv, o)) return *rc;
  const Problem p = make_problem(o);
  // Fail on an unwritable plot file now, not after the bounds' seconds of work.
  if (!o.plot_file.empty()) require_writable(o.plot_file, "--plot");
  const Bounds b = compute_bounds(p);
  if (o.json)
    print_json(p, b);
  else
    print_text(p, b);
  if (!o.plot_file.empty()) {
    plot(p, o.plot_file);
    if (!o.json) std::cout << "Plot written to " << o.plot_file << "\n";
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("rsd-applicability", [&] { return run(argc, argv); });
}
