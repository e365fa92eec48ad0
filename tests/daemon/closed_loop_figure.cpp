#include "tests/daemon/closed_loop_figure.hpp"

#include <plplot.h>

#include <algorithm>
#include <cmath>

#include "tools/report/plot_page.hpp"

namespace rsd::test {

namespace {

enum Colour { kWhite, kBlack, kRed, kBlue, kGreen, kGrey };

void curve(const Measured& m, double t0, int colour, int style) {
  std::vector<PLFLT> x, y;
  for (size_t i = 0; i < m.t.size(); ++i) x.push_back(m.t[i] - t0), y.push_back(std::log10(std::max(m.frame_rms[i], 1e-3)));
  plcol0(colour);
  pllsty(style);
  plwidth(3);
  plline(static_cast<PLINT>(x.size()), x.data(), y.data());
  pllsty(1);
}

}  // namespace

void plot_closed_loop(const std::string& file, const std::string& name, const Measured& nominal, const Measured& learned,
                      const Measured& truth) {
  if (nominal.t.empty()) return;
  tools::open_plot_page(file, 1200, 700,
                        {{kWhite, 255, 255, 255}, {kBlack, 0, 0, 0}, {kRed, 220, 20, 20}, {kBlue, 0, 70, 230},
                         {kGreen, 0, 150, 40}, {kGrey, 200, 200, 200}});
  const double t0 = nominal.t.front(), t1 = nominal.t.back();
  plvpor(0.09, 0.97, 0.12, 0.88);
  plwind(0, t1 - t0, -3.0, 1.0);  // 0.001 .. 10 px
  plcol0(kGrey);
  plbox("g", 0, 0, "g", 0, 0);
  plcol0(kBlack);
  plbox("bcnst", 0, 0, "bcnstvl", 0, 0);
  pllab("time since the first frame measured (s)", "rectified error, RMS per frame (px)", "");
  plmtex("t", 1.5, 0.5, 0.5, ("closed loop, " + name + ": error against the global-shutter truth").c_str());
  curve(nominal, t0, kRed, 1);
  curve(truth, t0, kGreen, 2);
  curve(learned, t0, kBlue, 1);
  char text[3][96];
  std::snprintf(text[0], sizeof text[0], "nominal calibration, %.3f px RMS", nominal.rms);
  std::snprintf(text[1], sizeof text[1], "learned by rsd-diagnose, %.3f px", learned.rms);
  std::snprintf(text[2], sizeof text[2], "true calibration, %.3f px", truth.rms);
  const int colours[3] = {kRed, kBlue, kGreen};
  for (int k = 0; k < 3; ++k) {
    plcol0(colours[k]);
    plmtex("t", -1.5 - 1.4 * k, 0.98, 1.0, text[k]);
  }
  plend();
}

}  // namespace rsd::test
