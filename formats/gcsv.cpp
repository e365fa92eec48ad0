#include "formats/gcsv.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <stdexcept>

#include "formats/number_text.hpp"

namespace rsd::formats {

namespace {

[[noreturn]] void gcsv_fail(const std::string& path, long line, const std::string& what) {
  throw std::runtime_error(path + ":" + std::to_string(line) + ": " + what);
}

// The fields of a line split at commas, blanks and a trailing CR trimmed from each.
std::vector<std::string> gcsv_fields(const std::string& line) {
  std::vector<std::string> out;
  size_t from = 0;
  while (true) {
    const size_t comma = line.find(',', from);
    std::string f = line.substr(from, comma == std::string::npos ? std::string::npos : comma - from);
    const size_t a = f.find_first_not_of(" \t\r"), b = f.find_last_not_of(" \t\r");
    out.push_back(a == std::string::npos ? std::string() : f.substr(a, b - a + 1));
    if (comma == std::string::npos) return out;
    from = comma + 1;
  }
}

double gcsv_number(const std::string& path, long line, const std::string& text, const std::string& what) {
  const std::optional<double> v = formats::parse_number(text);
  if (!v) gcsv_fail(path, line, what + " '" + text + "' is not a number");
  return *v;
}

// The header's key,value lines, up to the column header (returned in `columns`, with its line).
std::map<std::string, std::pair<std::string, long>> gcsv_header(std::ifstream& in, const std::string& path,
                                                           std::vector<std::string>& columns, long& line_no) {
  std::map<std::string, std::pair<std::string, long>> keys;
  std::string line;
  while (std::getline(in, line)) {
    ++line_no;
    const std::vector<std::string> f = gcsv_fields(line);
    if (f.size() == 1 && f[0].empty()) continue;
    if (f[0] == "t") {
      columns = f;
      return keys;
    }
    if (f.size() < 2) gcsv_fail(path, line_no, "expected key,value or the column header t,gx,gy,gz, got '" + line + "'");
    std::string value = f[1];
    for (size_t k = 2; k < f.size(); ++k) value += "," + f[k];  // a note may hold commas
    keys[f[0]] = {value, line_no};
  }
  gcsv_fail(path, line_no, "no column header (a line t,gx,gy,gz...) before the end of the file");
}

}  // namespace

GcsvLog read_gcsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string first;
  long line_no = 1;
  if (!std::getline(in, first)) gcsv_fail(path, 1, "empty file");
  if (const auto f = gcsv_fields(first)[0]; f != "GYROFLOW IMU LOG" && f != "CAMERA IMU LOG")
    gcsv_fail(path, 1, "not a gyroflow .gcsv log: the first line must be 'GYROFLOW IMU LOG' or 'CAMERA IMU LOG', got '" + f + "'");
  std::vector<std::string> columns;
  const auto keys = gcsv_header(in, path, columns, line_no);
  const long column_line = line_no;
  auto text = [&](const char* key) { const auto it = keys.find(key); return it == keys.end() ? std::string() : it->second.first; };
  auto scale = [&](const char* key) {
    const auto it = keys.find(key);
    if (it == keys.end()) gcsv_fail(path, column_line, std::string("no '") + key + "' line before the column header");
    const double s = gcsv_number(path, it->second.second, it->second.first, key);
    if (!(s > 0)) gcsv_fail(path, it->second.second, std::string(key) + " must be positive, got " + it->second.first);
    return s;
  };
  GcsvLog log;
  log.version = text("version"), log.id = text("id"), log.orientation = text("orientation");
  log.vendor = text("vendor"), log.videofilename = text("videofilename"), log.lensprofile = text("lensprofile");
  const double tscale = scale("tscale"), gscale = scale("gscale");
  if (const auto it = keys.find("frame_readout_time"); it != keys.end()) {
    const double ms = gcsv_number(path, it->second.second, it->second.first, "frame_readout_time");
    if (!(ms >= 0 && ms < 1000))
      gcsv_fail(path, it->second.second, "frame_readout_time must be at least 0 and under 1000 (ms: a frame's readout), got " + it->second.first);
    log.frame_readout_s = ms * 1e-3;
  }
  if (const auto it = keys.find("frame_readout_direction"); it != keys.end()) {
    const double d = gcsv_number(path, it->second.second, it->second.first, "frame_readout_direction");
    if (d != 0 && d != 1 && d != 2 && d != 3)
      gcsv_fail(path, it->second.second, "frame_readout_direction must be 0, 1, 2 or 3, got " + it->second.first);
    log.readout_direction = static_cast<int>(d);
  }
  if (columns.size() < 4 || columns[1] != "gx" || columns[2] != "gy" || columns[3] != "gz")
    gcsv_fail(path, column_line, "the column header must start with t,gx,gy,gz");
  std::string line;
  while (std::getline(in, line)) {
    ++line_no;
    const std::vector<std::string> f = gcsv_fields(line);
    if (f.size() == 1 && f[0].empty()) continue;
    if (f.size() < 4) gcsv_fail(path, line_no, "expected at least 4 fields (t,gx,gy,gz), got " + std::to_string(f.size()));
    dsp::GyroSample s;
    s.t = gcsv_number(path, line_no, f[0], "column t") * tscale;
    for (int k = 0; k < 3; ++k) s.w[k] = gcsv_number(path, line_no, f[1 + k], "column " + columns[1 + k]) * gscale;
    if (!log.gyro.empty() && s.t < log.gyro.back().t)
      gcsv_fail(path, line_no, "time goes back (" + f[0] + " after " + number_text(log.gyro.back().t / tscale) + ")");
    log.gyro.push_back(s);
  }
  if (log.gyro.size() < 2) gcsv_fail(path, line_no, "fewer than two gyro samples");
  return log;
}

}  // namespace rsd::formats
