#include "tools/common/cli_util.hpp"

#include <filesystem>

#include "rsd/version.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>

namespace rsd::tools {

// ---------------------------------------------------------------- parsing

std::optional<Eigen::Vector3d> parse_vec3(const std::string& s) {
  std::vector<std::string> parts(1);
  for (char c : s) {
    if (c == ',')
      parts.emplace_back();
    else if (c != ' ')
      parts.back() += c;
  }
  if (parts.size() != 3) return std::nullopt;
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    const auto x = parse_number(parts[i]);
    if (!x) return std::nullopt;
    v[i] = *x;
  }
  return v;
}

// ---------------------------------------------------------------- validators

CLI::Validator text_check(std::function<bool(const std::string&)> accepts,
                          const std::string& complaint, const std::string& description,
                          const std::string& name) {
  return CLI::Validator(
      [accepts = std::move(accepts), complaint](std::string& s) -> std::string {
        if (accepts(s)) return {};
        return complaint + ", got '" + s + "'";
      },
      description, name);
}

CLI::Validator positive(const std::string& unit) {
  return text_check(
      [](const std::string& s) {
        const auto x = parse_number(s);
        return x && *x > 0;
      },
      "expected a positive number (" + unit + ")", "> 0", "POSITIVE");
}

CLI::Validator finite_number(const std::string& unit) {
  return text_check([](const std::string& s) { return parse_number(s).has_value(); },
                    "expected a finite number (" + unit + ")", "", "FINITE");
}

CLI::Validator int_range(int lo, int hi) {
  return text_check(
      [lo, hi](const std::string& s) {
        const auto x = parse_number(s);
        return x && *x == std::floor(*x) && *x >= lo && *x <= hi;
      },
      "expected an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", "",
      "INT");
}

CLI::Validator open_interval(double lo, double hi, const std::string& what,
                             const std::string& name) {
  const std::string l = format_number(lo, 12), h = format_number(hi, 12);
  return text_check(
      [lo, hi](const std::string& s) {
        const auto x = parse_number(s);
        return x && *x > lo && *x < hi;
      },
      "expected " + what + " strictly between " + l + " and " + h, "(" + l + ", " + h + ")",
      name);
}

CLI::Validator vec3(const std::string& what) {
  return text_check([](const std::string& s) { return parse_vec3(s).has_value(); },
                    "expected three comma-separated finite numbers " + what, "X,Y,Z", "VEC3");
}

CLI::Validator file_extension(const std::vector<std::string>& extensions) {
  std::string listed, description;  // ".png or .svg", "FILE.png|FILE.svg"
  for (size_t i = 0; i < extensions.size(); ++i) {
    listed += (i == 0 ? "" : i + 1 == extensions.size() ? " or " : ", ") + extensions[i];
    description += (i == 0 ? "FILE" : "|FILE") + extensions[i];
  }
  return text_check(
      [extensions](const std::string& s) {
        for (const auto& e : extensions)  // a bare ".png" names no file
          if (s.size() > e.size() && s.ends_with(e)) return true;
        return false;
      },
      "file name must end in " + listed, description, "FILE");
}

// ---------------------------------------------------------------- errors and exit status

std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv) {
  // --version: "<program> <version>", the program as it was called (rsd-diagnose, ...).
  const std::string program = argc > 0 ? std::filesystem::path(argv[0]).filename().string() : app.get_name();
  app.set_version_flag("--version", program + " " + rsd::kVersion);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // app.exit prints help or the error; it returns 0 for --help, CLI11's own codes else.
    return app.exit(e) == 0 ? 0 : 2;
  }
  return std::nullopt;
}

int run_tool(const std::string& tool, const std::function<int()>& body) {
  try {
    return body();
  } catch (const UsageError& e) {
    std::cerr << tool << ": error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << tool << ": error: " << e.what() << "\n";
    return 1;
  }
}

void require_writable(const std::string& file, const std::string& option) {
  // Append mode: probing must not truncate a file the user may still want.
  std::ofstream probe(file, std::ios::binary | std::ios::app);
  if (!probe) throw UsageError(option + ": cannot write '" + file + "'");
}

// ---------------------------------------------------------------- formatting

std::string format_number(double x, int precision) {
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  if (std::isnan(x)) return "nan";
  std::ostringstream o;
  o.precision(precision);
  o << x;
  return o.str();
}

std::string format_fixed(double x, int decimals) {
  if (!std::isfinite(x)) return format_number(x);
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, x);
  return buf;
}

std::string format_vec3(const Eigen::Vector3d& v) {
  return "(" + format_number(v.x()) + ", " + format_number(v.y()) + ", " + format_number(v.z()) +
         ")";
}

std::string matrix_text(const Eigen::Matrix3d& m) {
  std::string s;
  // + 0.0: a product that came out -0 prints as 0.
  for (int k = 0; k < 9; ++k) s += (k ? "," : "") + format_number(m(k / 3, k % 3) + 0.0);
  return s;
}

std::string json_number(double x) {
  if (!std::isfinite(x)) return "null";
  std::ostringstream o;
  o.precision(12);
  o << x;
  return o.str();
}

std::string json_vec3(const Eigen::Vector3d& v) {
  return "[" + json_number(v.x()) + ", " + json_number(v.y()) + ", " + json_number(v.z()) + "]";
}

std::string json_string(const std::string& s) {
  std::string o = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o + "\"";
}

}  // namespace rsd::tools
