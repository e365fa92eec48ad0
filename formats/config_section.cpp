#include "formats/config_section.hpp"

#include <filesystem>

#include "formats/number_text.hpp"

namespace rsd::formats {

// ---------------------------------------------------------------- reading

void ConfigReader::value(const char* key, double& v, const char*) { v = m_.number(key, v); }
void ConfigReader::value(const char* key, int& v, const char*) { v = m_.integer(key, v); }
void ConfigReader::value(const char* key, unsigned& v, const char*) {
  const int i = m_.integer(key, static_cast<int>(v));
  if (i < 0) m_.fail(key, "must not be negative");
  v = static_cast<unsigned>(i);
}
void ConfigReader::value(const char* key, bool& v, const char*) { v = m_.boolean(key, v); }
void ConfigReader::value(const char* key, std::string& v, const char*) { v = m_.text(key, v); }
void ConfigReader::value(const char* key, Eigen::Vector3d& v, const char*) {
  if (!m_.has(key)) return void(m_.text(key, ""));  // marks the key known
  const auto n = m_.numbers(key, 3);
  v = Eigen::Vector3d(n[0], n[1], n[2]);
}
void ConfigReader::value(const char* key, Eigen::Matrix3d& v, const char*) {
  if (!m_.has(key)) return void(m_.text(key, ""));
  const auto n = m_.numbers(key, 9);
  for (int i = 0; i < 9; ++i) v(i / 3, i % 3) = n[static_cast<size_t>(i)];
}

void ConfigReader::section(const char* key, const std::function<void(ConfigSection&)>& body, const char*) {
  if (!m_.has(key)) return void(m_.text(key, ""));
  ConfigReader sub(m_.map(key));
  body(sub);
  sub.finish();
}

void ConfigReader::check(bool ok, const char* key, const std::string& why) {
  if (!ok) m_.fail(key, why);
}

void ConfigSection::path(const char* key, std::string& v, const char* comment) {
  std::string p = v;
  value(key, p, comment);
  if (!p.empty() && std::filesystem::path(p).is_relative() && !file().empty())
    p = (std::filesystem::path(file()).parent_path() / p).string();
  v = p;
}

void ConfigSection::pixel_format(const char* key, dsp::PixelFormat& v, const char* comment) {
  std::vector<std::string> names;
  for (int f = 0; f <= static_cast<int>(dsp::PixelFormat::BayerGbrg16); ++f) names.emplace_back(dsp::format_name(static_cast<dsp::PixelFormat>(f)));
  std::string text = dsp::format_name(v);
  if (!comment) comment = "mono8, mono16, rgb8, yuyv, nv12, i420, bayer_rggb8 (bggr, grbg, gbrg; 8 or 16)";
  if (choice_text(key, text, names, comment)) v = dsp::parse_format_name(text).value_or(v);
}

bool ConfigReader::choice_text(const char* key, std::string& text, const std::vector<std::string>& names, const char*) {
  if (!m_.has(key)) return void(m_.text(key, "")), false;
  text = m_.text(key, "");
  for (const auto& n : names)
    if (n == text) return true;
  std::string list;
  for (size_t i = 0; i < names.size(); ++i) list += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  m_.fail(key, "must be " + list);
}

// ---------------------------------------------------------------- printing defaults

namespace {

constexpr size_t kCommentColumn = 31;  // comments line up here, as in a hand-written file

std::string numbers(const double* v, int n) {
  std::string s = "[";
  for (int i = 0; i < n; ++i) s += (i ? ", " : "") + number_text(v[i]);
  return s + "]";
}

}  // namespace

void DefaultsPrinter::line(const char* key, const std::string& value, const char* comment) {
  std::string l(static_cast<size_t>(indent_), ' ');
  l += key;
  l += ":";
  if (!value.empty()) l += " " + value;
  if (comment) l += std::string(l.size() < kCommentColumn ? kCommentColumn - l.size() : 1, ' ') + "# " + comment;
  out_ << l << "\n";
}

void DefaultsPrinter::value(const char* key, double& v, const char* c) { line(key, number_text(v), c); }
void DefaultsPrinter::value(const char* key, int& v, const char* c) { line(key, std::to_string(v), c); }
void DefaultsPrinter::value(const char* key, unsigned& v, const char* c) { line(key, std::to_string(v), c); }
void DefaultsPrinter::value(const char* key, bool& v, const char* c) { line(key, v ? "true" : "false", c); }
void DefaultsPrinter::value(const char* key, std::string& v, const char* c) { line(key, v.empty() ? "\"\"" : v, c); }
void DefaultsPrinter::value(const char* key, Eigen::Vector3d& v, const char* c) { line(key, numbers(v.data(), 3), c); }
void DefaultsPrinter::value(const char* key, Eigen::Matrix3d& v, const char* c) {
  const Eigen::Matrix<double, 3, 3, Eigen::RowMajor> r = v;
  line(key, numbers(r.data(), 9), c);
}

void DefaultsPrinter::section(const char* key, const std::function<void(ConfigSection&)>& body, const char* comment) {
  line(key, "", comment);
  DefaultsPrinter sub(indent_ + 2);
  body(sub);
  out_ << sub.text();
}

void DefaultsPrinter::note(const std::string& text) { out_ << std::string(static_cast<size_t>(indent_), ' ') << "# " << text << "\n"; }

bool DefaultsPrinter::choice_text(const char* key, std::string& text, const std::vector<std::string>& names, const char* comment) {
  std::string others;
  for (const auto& n : names)
    if (n != text) others += (others.empty() ? "or " : ", ") + n;
  line(key, text, comment ? comment : others.c_str());
  return false;
}

}  // namespace rsd::formats
