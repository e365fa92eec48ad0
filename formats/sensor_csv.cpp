#include "formats/sensor_csv.hpp"

#include <cmath>
#include <fstream>
#include <stdexcept>

#include "formats/number_text.hpp"

namespace rsd::formats {

namespace {

constexpr const char* kColumnNames[4] = {"t", "wx", "wy", "wz"};

// Fields separated by the line's first comma, semicolon or tab kind (blanks around a field
// trimmed), else by runs of blanks.
std::vector<std::string> csv_fields(const std::string& line) {
  const size_t sep_at = line.find_first_of(",;\t");
  const char sep = sep_at == std::string::npos ? ' ' : line[sep_at];
  std::vector<std::string> out;
  std::string cur;
  auto trimmed = [](const std::string& f) {
    const size_t a = f.find_first_not_of(" \r"), b = f.find_last_not_of(" \r");
    return a == std::string::npos ? std::string() : f.substr(a, b - a + 1);
  };
  for (char c : line) {
    if (c == sep || (sep == ' ' && c == '\r')) {
      if (sep != ' ' || !cur.empty()) out.push_back(trimmed(cur));
      cur.clear();
      continue;
    }
    cur += c;
  }
  if (!trimmed(cur).empty() || (sep != ' ' && !out.empty())) out.push_back(trimmed(cur));
  return out;
}

[[noreturn]] void csv_error(const std::string& path, long line, const std::string& what) {
  throw std::runtime_error(path + ":" + std::to_string(line) + ": " + what);
}

// Calls row(fields, line number) for every data line; the first non-blank line is a header when
// its first field is not a number.
template <class Row>
void for_each_csv_row(const std::string& path, Row row) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string line;
  bool first = true;
  for (long n = 1; std::getline(in, line); ++n) {
    const std::vector<std::string> f = csv_fields(line);
    if (f.empty() || f[0].rfind('#', 0) == 0) continue;
    if (first && !rsd::formats::parse_number(f[0])) {
      first = false;
      continue;  // a header
    }
    first = false;
    row(f, n);
  }
}

}  // namespace

GyroColumns parse_gyro_columns(const std::string& spec) {
  GyroColumns c;
  c.spec = spec;
  c.index = {-1, -1, -1, -1};
  const std::vector<std::string> names = csv_fields(spec);
  for (size_t k = 0; k < names.size(); ++k) {
    if (names[k] == "-") continue;
    int q = 0;
    while (q < 4 && names[k] != kColumnNames[q]) ++q;
    if (q == 4) throw std::invalid_argument("'" + names[k] + "' is not t, wx, wy, wz or - (in '" + spec + "')");
    if (c.index[q] >= 0) throw std::invalid_argument("'" + names[k] + "' named twice (in '" + spec + "')");
    c.index[q] = static_cast<int>(k);
  }
  for (int q = 0; q < 4; ++q)
    if (c.index[q] < 0) throw std::invalid_argument(std::string("no column '") + kColumnNames[q] + "' (in '" + spec + "')");
  c.count = static_cast<int>(names.size());
  return c;
}

double time_unit_seconds(const std::string& unit) {
  if (unit == "s") return 1;
  if (unit == "ms") return 1e-3;
  if (unit == "us") return 1e-6;
  if (unit == "ns") return 1e-9;
  throw std::invalid_argument("time unit '" + unit + "' is not s, ms, us or ns");
}

std::vector<dsp::GyroSample> read_gyro_csv(const std::string& path, const GyroColumns& columns, double unit_s) {
  std::vector<dsp::GyroSample> out;
  for_each_csv_row(path, [&](const std::vector<std::string>& f, long n) {
    if (static_cast<int>(f.size()) < columns.count)
      csv_error(path, n, std::to_string(f.size()) + " fields; the columns " + columns.spec + " need " + std::to_string(columns.count));
    double v[4];
    for (int q = 0; q < 4; ++q) {
      const std::string& text = f[static_cast<size_t>(columns.index[q])];
      const std::optional<double> x = rsd::formats::parse_number(text);
      if (!x) csv_error(path, n, std::string("field '") + kColumnNames[q] + "' (column " + std::to_string(columns.index[q] + 1) + "): '" + text + "' is not a number");
      v[q] = *x;
    }
    const double t = v[0] * unit_s;
    if (!out.empty() && t < out.back().t)
      csv_error(path, n, "time " + number_text(v[0]) + " is before the previous sample's: gyro samples must not go back in time");
    out.push_back({t, Eigen::Vector3d(v[1], v[2], v[3])});
  });
  if (out.size() < 2) throw std::runtime_error(path + ": fewer than two gyro samples");
  return out;
}

std::vector<double> read_frame_times(const std::string& path, double unit_s) {
  std::vector<double> out;
  for_each_csv_row(path, [&](const std::vector<std::string>& f, long n) {
    const std::optional<double> x = rsd::formats::parse_number(f[0]);
    if (!x) csv_error(path, n, "'" + f[0] + "' is not a number (a frame time)");
    const double t = *x * unit_s;
    if (!out.empty() && !(t > out.back()))
      csv_error(path, n, "frame time " + number_text(*x) + " is not after the previous frame's: frame times must increase");
    out.push_back(t);
  });
  if (out.empty()) throw std::runtime_error(path + ": no frame times");
  return out;
}

}  // namespace rsd::formats
