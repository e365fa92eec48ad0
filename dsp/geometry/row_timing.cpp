#include "dsp/geometry/row_timing.hpp"

#include <cmath>

namespace rsd::dsp {

std::string_view to_string(Readout r) {
  return r == Readout::TopToBottom ? "top_to_bottom" : "bottom_to_top";
}

bool parse_readout(std::string_view s, Readout& out) {
  if (s == "top_to_bottom") {
    out = Readout::TopToBottom;
    return true;
  }
  if (s == "bottom_to_top") {
    out = Readout::BottomToTop;
    return true;
  }
  return false;
}

double row_rate_from_line_delay(double line_delay_s) { return 1.0 / line_delay_s; }
double line_delay_from_row_rate(double row_rate_hz) { return 1.0 / std::abs(row_rate_hz); }
double frame_readout_from_line_delay(double line_delay_s, int rows) { return rows * line_delay_s; }
double line_delay_from_frame_readout(double readout_s, int rows) { return readout_s / rows; }

RowTiming RowTiming::full_frame(int height, double fps, Readout dir) {
  RowTiming t;
  t.height = height;
  t.frame_rate_hz = fps;
  t.line_delay_s = 1.0 / (height * fps);
  t.readout = dir;
  return t;
}

int RowTiming::first_row_read() const {
  if (first_row >= 0) return first_row;
  return readout == Readout::TopToBottom ? 0 : height - 1;
}

double RowTiming::r() const {
  const double rate = row_rate_from_line_delay(line_delay_s);
  return readout == Readout::TopToBottom ? rate : -rate;
}

// row_at(0) = -v0 must be the first row read.
double RowTiming::v0() const { return -static_cast<double>(first_row_read()); }

}  // namespace rsd::dsp
