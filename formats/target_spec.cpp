#include "formats/target_spec.hpp"

#include <sstream>
#include <stdexcept>
#include <vector>

#include "formats/number_text.hpp"

namespace rsd::formats {

using dsp::TargetKind;
using dsp::TargetSpec;

namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::stringstream in(s);
  for (std::string p; std::getline(in, p, sep);) parts.push_back(p);
  return parts;
}

// "9x7" -> cols 9, rows 7.
bool parse_size(const std::string& s, int& cols, int& rows) {
  const size_t x = s.find('x');
  if (x == std::string::npos) return false;
  const auto c = formats::parse_number(s.substr(0, x)), r = formats::parse_number(s.substr(x + 1));
  if (!c || !r || *c != static_cast<int>(*c) || *r != static_cast<int>(*r) || *c < 1 || *r < 1) return false;
  cols = static_cast<int>(*c), rows = static_cast<int>(*r);
  return true;
}

}  // namespace

dsp::TargetSpec parse_target(const std::string& text) {
  const std::string expected =
      "expected checkerboard:COLSxROWS:SQUARE_M (inner corners) or aprilgrid:COLSxROWS:TAG_M[:SPACING], got '" + text + "'";
  const std::vector<std::string> p = split(text, ':');
  dsp::TargetSpec s;
  if (p.size() < 3) throw std::invalid_argument(expected);
  if (p[0] == "checkerboard" && p.size() == 3) s.kind = dsp::TargetKind::Checkerboard;
  else if (p[0] == "aprilgrid" && p.size() <= 4) s.kind = dsp::TargetKind::AprilGrid;
  else throw std::invalid_argument(expected);
  const auto size = formats::parse_number(p[2]);
  if (!parse_size(p[1], s.cols, s.rows) || !size || !(*size > 0)) throw std::invalid_argument(expected);
  s.spacing_m = *size;
  if (p.size() == 4) {
    const auto gap = formats::parse_number(p[3]);
    if (!gap || !(*gap > 0)) throw std::invalid_argument(expected);
    s.tag_spacing = *gap;
  }
  if (s.kind == dsp::TargetKind::Checkerboard && (s.cols < 2 || s.rows < 2 || s.cols == s.rows))
    throw std::invalid_argument("checkerboard: inner corners COLSxROWS must be at least 2x2 and differ (a square board's "
                                "orientation is ambiguous), got '" + text + "'");
  if (s.kind == dsp::TargetKind::AprilGrid && s.rows * s.cols > 587)
    throw std::invalid_argument("aprilgrid: at most 587 tags (tag36h11), got '" + text + "'");
  return s;
}

}  // namespace rsd::formats
