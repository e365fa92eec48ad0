// rsd-paper-experiment: the simulation of Meingast, Geyer, Sastry (2005), Sec. 4 and its
// fig. simfigs — two-view bundle adjustment of rolling-shutter images with the rolling-shutter
// model and with the perspective model, over the paper's 4 speeds x 6 noise levels.
// Writes DIR/paper-experiment.csv, .png and .svg and prints the result table (Markdown).
// The computation is dsp/analysis/paper_experiment.hpp; docs/paper-experiment.md states the set-up.
#include <CLI/CLI.hpp>
#include <plplot.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <exception>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "tools/common/cli_util.hpp"
#include "dsp/analysis/paper_experiment.hpp"
#include "tools/report/plot_page.hpp"

using namespace rsd::dsp;
using namespace rsd::tools;

namespace {

constexpr size_t kRs = static_cast<size_t>(ProjectionModel::RollingShutter);
constexpr size_t kPersp = static_cast<size_t>(ProjectionModel::Perspective);

// ---------------------------------------------------------------- options

struct Options {
  std::string out;
  int trials = 500;
  int threads = 2;
  std::uint64_t seed = 1;
};

constexpr const char* kDescription =
    "rsd-paper-experiment: the simulation of Meingast, Geyer, Sastry (2005), Sec. 4.\n"
    "100 random points, two cameras about 10 m away (640 x 480, 40 deg horizontal field of\n"
    "view, 15 fps, r = 7200 rows/s), each moving with v = (0, v_y, 0) in its own frame during\n"
    "its readout; v_y in {1.875, 3.75, 5.625, 7.5} km/h and pixel noise sigma in {0.5, 1.33,\n"
    "2.16, 3, 3.83, 4.66} px. Per trial, two-view bundle adjustment (Ceres) with the\n"
    "rolling-shutter model eq. (4) and with the perspective model, from the\n"
    "same perturbed truth. Errors: RMS reprojection (px), |log(R0^-1 R)| (deg), angle of the\n"
    "translation direction (deg). See docs/paper-experiment.md.\n\n"
    "Writes DIR/paper-experiment.csv, DIR/paper-experiment.png and DIR/paper-experiment.svg;\n"
    "prints the table (Markdown) on stdout and one progress line per cell on stderr.\n"
    "Exit status: 0 on success, 2 on bad arguments, 1 on other errors.";

std::optional<int> parse_options(int argc, char** argv, Options& o) {
  CLI::App app(kDescription, "rsd-paper-experiment");
  app.add_option("--out", o.out, "Output directory (created if missing)")->required();
  app.add_option("--trials", o.trials, "Trials per cell (velocity x noise)")
      ->check(int_range(1, 1000000))
      ->capture_default_str();
  app.add_option("--threads", o.threads, "Worker threads (cells run in parallel)")
      ->check(int_range(1, 256))
      ->capture_default_str();
  app.add_option("--seed", o.seed, "Seed: trial k of every cell is drawn from (seed, k)")
      ->capture_default_str();
  return parse_command_line(app, argc, argv);
}

// ---------------------------------------------------------------- running the cells

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

void report_cell(const CellResult& r, size_t done, size_t total, double cell_s, double total_s) {
  const auto& rs = r.models[kRs];
  const auto& pe = r.models[kPersp];
  std::cerr << "[" << done << "/" << total << "] v_y " << format_number(r.cell.vy_kmh)
            << " km/h, sigma " << format_number(r.cell.sigma_px) << " px: rotation "
            << format_number(rs.rot_deg.mean, 3) << " (RS) vs " << format_number(pe.rot_deg.mean, 3)
            << " (persp) deg, translation " << format_number(rs.trans_deg.mean, 3) << " vs "
            << format_number(pe.trans_deg.mean, 3) << " deg; " << format_fixed(cell_s, 1)
            << " s, elapsed " << format_fixed(total_s, 1) << " s\n";
}

// Cells are handed out one at a time to `threads` workers; each result goes to its cell's
// slot, so the output does not depend on the scheduling.
std::vector<CellResult> run_all(const Options& o, const std::vector<Cell>& cells) {
  const ExperimentSetup setup;
  std::vector<CellResult> results(cells.size());
  std::atomic<size_t> next{0};
  size_t done = 0;
  std::mutex report;
  std::exception_ptr failure;  // an exception must not escape a thread: rethrown after join
  const auto t0 = Clock::now();
  auto worker = [&] {
    try {
      for (size_t k; (k = next++) < cells.size();) {
        const auto t_cell = Clock::now();
        results[k] = run_cell(setup, o.seed, cells[k], o.trials);
        std::lock_guard lock(report);
        report_cell(results[k], ++done, cells.size(), seconds_since(t_cell), seconds_since(t0));
      }
    } catch (...) {
      std::lock_guard lock(report);
      if (!failure) failure = std::current_exception();
      next = cells.size();  // stop the other workers early
    }
  };
  std::vector<std::thread> pool;
  for (int i = 0; i < o.threads; ++i) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (failure) std::rethrow_exception(failure);
  return results;
}

// ---------------------------------------------------------------- CSV and table

void write_csv(const std::vector<CellResult>& results, const std::string& file) {
  std::ofstream f(file);
  f << "velocity_kmh,sigma_px,model,trials,reproj_mean,reproj_std,rot_deg_mean,rot_deg_std,"
       "trans_deg_mean,trans_deg_std,reproj_median,rot_deg_median,trans_deg_median,"
       "not_converged\n";
  for (const auto& r : results)
    for (ProjectionModel m : {ProjectionModel::RollingShutter, ProjectionModel::Perspective}) {
      const ModelSummary& s = r.models[static_cast<size_t>(m)];
      f << format_number(r.cell.vy_kmh, 6) << "," << format_number(r.cell.sigma_px, 6) << ","
        << to_string(m) << "," << s.trials << "," << format_number(s.reproj_px.mean, 6) << ","
        << format_number(s.reproj_px.std, 6) << "," << format_number(s.rot_deg.mean, 6) << ","
        << format_number(s.rot_deg.std, 6) << "," << format_number(s.trans_deg.mean, 6) << ","
        << format_number(s.trans_deg.std, 6) << "," << format_number(s.reproj_px.median, 6) << ","
        << format_number(s.rot_deg.median, 6) << "," << format_number(s.trans_deg.median, 6) << ","
        << s.not_converged << "\n";
    }
  if (!f) throw std::runtime_error("cannot write '" + file + "'");
}

std::string pm(const Stats& s, int decimals) {
  return format_fixed(s.mean, decimals) + " ± " + format_fixed(s.std, decimals);
}

// One Markdown row per cell: both models side by side, mean ± std.
void print_table(const std::vector<CellResult>& results) {
  std::cout << "| v_y (km/h) | sigma (px) | reproj RS (px) | reproj persp (px) | rot RS (deg) | "
               "rot persp (deg) | transl RS (deg) | transl persp (deg) |\n"
               "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n";
  for (const auto& r : results) {
    const auto& rs = r.models[kRs];
    const auto& pe = r.models[kPersp];
    std::cout << "| " << format_number(r.cell.vy_kmh) << " | " << format_number(r.cell.sigma_px)
              << " | " << pm(rs.reproj_px, 3) << " | " << pm(pe.reproj_px, 3) << " | "
              << pm(rs.rot_deg, 3) << " | " << pm(pe.rot_deg, 3) << " | " << pm(rs.trans_deg, 3)
              << " | " << pm(pe.trans_deg, 3) << " |\n";
  }
}

// ---------------------------------------------------------------- the figure

enum Colour : PLINT { kWhite = 0, kBlack = 1, kBlue = 2, kRed = 3, kLightGrey = 4, kGrey = 5 };
constexpr PLFLT kLineWidth = 2.5;
constexpr PLFLT kSigmaMax = 5.0;
// PLplot's character size follows the page size: on this 1500 x 1500 page its default is
// too large for 12 panels, so every size below is a multiple of this.
constexpr PLFLT kText = 0.55;

// The three error measures, the columns of the paper's fig. simfigs.
struct Measure {
  const char* title;
  const Stats& (*of)(const ModelSummary&);
};
const Measure kMeasures[3] = {
    {"RMS reprojection error (px)",
     [](const ModelSummary& s) -> const Stats& { return s.reproj_px; }},
    {"rotation error |log R#d0#u#u-1#d R| (deg)",
     [](const ModelSummary& s) -> const Stats& { return s.rot_deg; }},
    {"translation direction error (deg)",
     [](const ModelSummary& s) -> const Stats& { return s.trans_deg; }},
};

// Mean with +-1 standard error of the mean, for one speed, model and measure.
struct Series {
  std::vector<PLFLT> sigma, mean, lo, hi;
};

Series series(const std::vector<CellResult>& results, double vy, size_t model, const Measure& m) {
  Series s;
  for (const auto& r : results) {
    if (r.cell.vy_kmh != vy) continue;
    const ModelSummary& ms = r.models[model];
    const Stats& st = m.of(ms);
    const double sem = st.std / std::sqrt(static_cast<double>(std::max(ms.trials, 1)));
    s.sigma.push_back(r.cell.sigma_px);
    s.mean.push_back(st.mean);
    s.lo.push_back(st.mean - sem);
    s.hi.push_back(st.mean + sem);
  }
  return s;
}

// One y range per column (shared by the speeds) so that the growth with v_y shows.
double column_max(const std::vector<CellResult>& results, const Measure& m) {
  double y = 0;
  for (double vy : kPaperSpeedsKmh)
    for (size_t model : {kRs, kPersp})
      for (double h : series(results, vy, model, m).hi) y = std::max(y, h);
  return 1.08 * y;
}

void open_page(const std::string& file) {
  open_plot_page(file, 1500, 1500,
                 {{kWhite, 255, 255, 255}, {kBlack, 0, 0, 0}, {kBlue, 0, 70, 230}, {kRed, 220, 20, 20},
                  {kLightGrey, 210, 210, 210}, {kGrey, 90, 90, 90}});
}

// Panel (row, col) of the 4 x 3 grid in normalised page coordinates; row 0 on top.
void panel_viewport(int row, int col) {
  const double left = 0.085, right = 0.985, top = 0.885, bottom = 0.10;
  const double hgap = 0.055, vgap = 0.035;
  const double w = (right - left - 2 * hgap) / 3, h = (top - bottom - 3 * vgap) / 4;
  const double x0 = left + col * (w + hgap), y1 = top - row * (h + vgap);
  plvpor(x0, x0 + w, y1 - h, y1);
}

void draw_series(const Series& s, PLINT colour, PLINT style) {
  const PLINT n = static_cast<PLINT>(s.sigma.size());
  plcol0(colour);
  plwidth(kLineWidth);
  pllsty(style);
  plline(n, s.sigma.data(), s.mean.data());
  pllsty(1);
  plwidth(1.5);
  plerry(n, s.sigma.data(), s.lo.data(), s.hi.data());
  plssym(0, 0.9);
  plpoin(n, s.sigma.data(), s.mean.data(), style == 1 ? 17 : 22);  // filled dot / square
}

void draw_panel(const std::vector<CellResult>& results, int row, int col, double y_max) {
  const double vy = kPaperSpeedsKmh[kPaperSpeedsKmh.size() - 1 - row];  // fastest on top
  panel_viewport(row, col);
  plwind(0, kSigmaMax, 0, y_max);
  plschr(0, kText * 0.75);
  plcol0(kLightGrey);
  plwidth(1);
  plbox("g", 1, 0, "g", 0, 0);
  plcol0(kBlack);
  plbox(row == 3 ? "bcnst" : "bcst", 1, 0, "bcnstv", 0, 0);
  if (row == 3) pllab("pixel noise #gs (px)", "", "");
  if (col == 0) {
    plschr(0, kText * 0.95);
    plmtex("l", 6.2, 0.5, 0.5, ("v#dy#u = " + format_number(vy) + " km/h").c_str());
  }
  if (row == 0) {
    plschr(0, kText * 0.9);
    plmtex("t", 1.2, 0.5, 0.5, kMeasures[col].title);
  }
  draw_series(series(results, vy, kPersp, kMeasures[col]), kRed, 2);
  draw_series(series(results, vy, kRs, kMeasures[col]), kBlue, 1);
}

// The set-up in two lines, from the values the experiment used.
std::array<std::string, 2> setup_lines(const ExperimentSetup& s, int trials) {
  const double hfov = 2 * std::atan(0.5 * s.cam.width / s.cam.fx) * 180 / 3.14159265358979323846;
  return {std::to_string(s.cam.width) + " x " + std::to_string(s.cam.height) + " px, " +
              format_number(hfov, 3) + "#uo#d horizontal field of view, " +
              format_number(s.timing.frame_rate_hz) + " fps, r = " +
              format_number(s.timing.r(), 6) + " rows/s; " + std::to_string(s.points) +
              " points, cameras " + format_number(s.distance_min_m) + "-" +
              format_number(s.distance_max_m) + " m from the cloud",
          "v = (0, v#dy#u, 0), #gw = 0 in each camera's frame; mean of " +
              std::to_string(trials) + " trials per point, bars #(2233)1 standard error of the mean"};
}

void draw_title(int trials) {
  plvpor(0.0, 1.0, 0.0, 1.0);
  plwind(0, 1, 0, 1);
  plcol0(kBlack);
  plschr(0, kText * 1.1);
  const char* title =
      "Two-view bundle adjustment of rolling-shutter images (Meingast, Geyer, Sastry 2005, Sec. 4)";
  plmtex("t", -1.4, 0.5, 0.5, title);
  plschr(0, kText * 0.8);
  const auto lines = setup_lines(ExperimentSetup{}, trials);
  plmtex("t", -4.4, 0.5, 0.5, lines[0].c_str());
  plmtex("t", -6.0, 0.5, 0.5, lines[1].c_str());
}

void draw_legend() {
  plvpor(0.30, 0.70, 0.01, 0.045);
  plwind(0, 1, 0, 1);
  const PLFLT y = 0.5;
  const PLFLT xs[2][2] = {{0.0, 0.09}, {0.56, 0.65}};
  const PLINT colours[2] = {kBlue, kRed}, styles[2] = {1, 2}, markers[2] = {17, 22};
  const char* labels[2] = {"rolling-shutter model", "perspective model"};
  for (int i = 0; i < 2; ++i) {
    PLFLT lx[2] = {xs[i][0], xs[i][1]}, ly[2] = {y, y}, mx = 0.5 * (lx[0] + lx[1]);
    PLFLT my = y;
    plcol0(colours[i]);
    plwidth(kLineWidth);
    pllsty(styles[i]);
    plline(2, lx, ly);
    pllsty(1);
    plpoin(1, &mx, &my, markers[i]);
    plcol0(kBlack);
    plschr(0, kText * 0.95);
    plptex(xs[i][1] + 0.02, y, 1, 0, 0, labels[i]);
  }
}

void plot(const std::vector<CellResult>& results, int trials, const std::string& file) {
  double y_max[3];
  for (int c = 0; c < 3; ++c) y_max[c] = column_max(results, kMeasures[c]);
  open_page(file);
  for (int row = 0; row < 4; ++row)
    for (int col = 0; col < 3; ++col) draw_panel(results, row, col, y_max[col]);
  draw_title(trials);
  draw_legend();
  plend();
}

// ---------------------------------------------------------------- main

int run(int argc, char** argv) {
  Options o;
  if (const auto rc = parse_options(argc, argv, o)) return *rc;
  // A directory that cannot be created shows up as an unwritable file just below.
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  const std::string base = (std::filesystem::path(o.out) / "paper-experiment").string();
  for (const char* ext : {".csv", ".png", ".svg"}) require_writable(base + ext, "--out");
  const auto t0 = Clock::now();
  const std::vector<CellResult> results = run_all(o, paper_cells());
  std::cerr << "all " << results.size() << " cells x " << o.trials << " trials in "
            << format_fixed(seconds_since(t0), 1) << " s on " << o.threads << " thread(s)\n";
  write_csv(results, base + ".csv");
  plot(results, o.trials, base + ".png");
  plot(results, o.trials, base + ".svg");
  print_table(results);
  std::cerr << "wrote " << base << ".csv, .png, .svg\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("rsd-paper-experiment", [&] { return run(argc, argv); });
}
