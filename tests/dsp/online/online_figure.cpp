#include "tests/dsp/online/online_figure.hpp"

#include <plplot.h>

#include <algorithm>
#include <functional>

#include "tools/report/plot_page.hpp"

namespace rsd::test {

namespace {

enum Colour { kWhite, kBlack, kBlue, kGreen, kGrey, kLightBlue };

using Value = std::function<double(const dsp::OnlineCalibration&)>;

// One panel: the estimate (blue) within +-1 sigma (light blue), the truth (green, dashed).
void panel(const OnlineTrace& tr, const OnlineTruth& truth, const Value& value, double y0, double y1, const char* label,
           double top, double bottom, bool last) {
  const double t1 = tr.t.back() + 1;
  plvpor(0.12, 0.97, bottom, top);
  plwind(0, t1, y0, y1);
  plcol0(kGrey);
  plbox("g", 0, 0, "g", 0, 0);
  plcol0(kBlack);
  plbox(last ? "bcnst" : "bcst", 0, 0, "bcnstv", 0, 0);
  plmtex("l", 5.0, 0.5, 0.5, label);
  std::vector<PLFLT> x, lo, hi, v;
  for (size_t i = 0; i < tr.t.size(); ++i) {
    dsp::OnlineCalibration up = tr.est[i].value, down = tr.est[i].value;
    up.time_offset_s += tr.est[i].sigma.time_offset_s, down.time_offset_s -= tr.est[i].sigma.time_offset_s;
    up.line_delay_s += tr.est[i].sigma.line_delay_s, down.line_delay_s -= tr.est[i].sigma.line_delay_s;
    up.gyro_bias += tr.est[i].sigma.gyro_bias, down.gyro_bias -= tr.est[i].sigma.gyro_bias;
    x.push_back(tr.t[i]), v.push_back(value(tr.est[i].value));
    lo.push_back(std::clamp(value(down), y0, y1)), hi.push_back(std::clamp(value(up), y0, y1));
  }
  plwidth(1);
  plcol0(kLightBlue);
  for (size_t i = 0; i < x.size(); ++i) pljoin(x[i], lo[i], x[i], hi[i]);
  const double step = truth.step_at_s >= 0 ? truth.step_at_s : t1;
  plcol0(kGreen);
  pllsty(2);
  plwidth(2);
  pljoin(0, value(truth.before), step, value(truth.before));
  if (truth.step_at_s >= 0) pljoin(step, value(truth.after), t1, value(truth.after));
  pllsty(1);
  plcol0(kBlue);
  plwidth(3);
  plline(static_cast<PLINT>(x.size()), x.data(), v.data());
  plpoin(static_cast<PLINT>(x.size()), x.data(), v.data(), 17);
  plwidth(1);
}

}  // namespace

void plot_online_trace(const std::string& file, const std::string& title, const OnlineTrace& tr, const OnlineTruth& truth) {
  if (tr.t.empty()) return;
  tools::open_plot_page(file, 1000, 900,
                        {{kWhite, 255, 255, 255}, {kBlack, 0, 0, 0}, {kBlue, 0, 70, 230}, {kGreen, 0, 150, 40},
                         {kGrey, 210, 210, 210}, {kLightBlue, 140, 180, 255}});
  const double ld = truth.nominal_line_delay_s, off = truth.before.time_offset_s * 1e3;
  const double off2 = truth.after.time_offset_s * 1e3;
  panel(tr, truth, [](const dsp::OnlineCalibration& c) { return c.time_offset_s * 1e3; }, std::min(off, off2) - 2,
        std::max(off, off2) + 2, "time offset (ms)", 0.93, 0.67, false);
  plmtex("t", 1.5, 0.5, 0.5, title.c_str());
  panel(tr, truth, [ld](const dsp::OnlineCalibration& c) { return c.line_delay_s / ld; }, 0.95, 1.35,
        "line delay / nominal", 0.64, 0.38, false);
  panel(tr, truth, [](const dsp::OnlineCalibration& c) { return c.gyro_bias.z() * 1e3; }, 0, 20, "gyro bias z (mrad/s)", 0.35,
        0.09, true);
  plcol0(kBlack);
  pllab("time since the first frame (s)", "", "");
  plend();
}

}  // namespace rsd::test
