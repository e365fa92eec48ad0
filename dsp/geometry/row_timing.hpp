// When each scanline is read: the paper's eq. (1), v_cam(t0 + t) = r t - v0.
//
// r is the signed row rate (rows per second; negative for bottom-to-top readout) and
// v0 is chosen so that the first row read is read at t = 0 (frame start t0). The
// line delay is 1/|r|. A frame period longer than the readout leaves an inter-frame
// delay d (vertical blanking): d = 1/f - height/|r|, zero when r = rows * fps.
#pragma once

#include <string_view>

namespace rsd::dsp {

enum class Readout { TopToBottom, BottomToTop };

std::string_view to_string(Readout r);
// Parses "top_to_bottom" / "bottom_to_top"; returns false on anything else.
bool parse_readout(std::string_view s, Readout& out);

// Conversions between line delay, frame readout time and row rate.
double row_rate_from_line_delay(double line_delay_s);               // |r| = 1 / delay
double line_delay_from_row_rate(double row_rate_hz);                // delay = 1 / |r|
double frame_readout_from_line_delay(double line_delay_s, int rows);  // rows * delay
double line_delay_from_frame_readout(double readout_s, int rows);     // readout / rows

struct RowTiming {
  int height = 480;
  double line_delay_s = 1.0 / (480 * 30.0);  // default: readout fills a 30 fps frame
  Readout readout = Readout::TopToBottom;
  double frame_rate_hz = 30.0;
  double exposure_s = 0.0;   // exposure of one row; its mid-point lags its start by half
  int first_row = -1;        // row read first; -1 means the readout's natural first row

  // A timing whose readout fills the whole frame period (the paper's d = 0 case).
  static RowTiming full_frame(int height, double fps, Readout dir = Readout::TopToBottom);

  // The paper's r (rows/s, signed by readout direction) and v0 (rows), eq. (1).
  double r() const;
  double v0() const;
  int first_row_read() const;

  double frame_period_s() const { return 1.0 / frame_rate_hz; }
  double frame_readout_s() const { return frame_readout_from_line_delay(line_delay_s, height); }
  // The paper's d: the frame period minus the readout time.
  double inter_frame_delay_s() const { return frame_period_s() - frame_readout_s(); }

  // Time (after frame start t0) at which the readout passes (possibly fractional) row v,
  // i.e. (v + v0) / r. This is the start of that row's exposure window when timestamps
  // are start-of-exposure.
  double row_time(double v) const { return (v + v0()) / r(); }
  // Row under the readout at time t after frame start, eq. (1): r t - v0.
  double row_at(double t) const { return r() * t - v0(); }
  // Mid-point of row v's exposure, relative to frame start.
  double row_mid_exposure(double v) const { return row_time(v) + 0.5 * exposure_s; }
};

}  // namespace rsd::dsp
