// Helpers shared by the command-line tools (rsd-applicability, rsd-sim, rsd-calib,
// rsd-diagnose): strict parsing of numbers and vectors, CLI11 validators with messages
// that say what was expected, number formatting for text and JSON output, and the
// tools' common exit-status convention (0 success, 2 bad arguments, 1 other errors).
#pragma once

#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "formats/number_text.hpp"

namespace rsd::tools {

// ---------------------------------------------------------------- parsing

// Strict number parsing: the whole string must be a finite number.
using formats::parse_number;

// Three comma-separated finite numbers ("1,2.5,-3"); spaces are ignored.
std::optional<Eigen::Vector3d> parse_vec3(const std::string& s);

// ---------------------------------------------------------------- validators
//
// CLI11 validators see the raw text. On failure their message is "<complaint>, got
// '<text>'", and CLI11 prefixes the option's name: "--fps: expected a positive number
// (frames per second), got '0'". `description` is what --help shows after the type.

// The building block of the others: accepts the text when `accepts` returns true.
CLI::Validator text_check(std::function<bool(const std::string&)> accepts,
                          const std::string& complaint, const std::string& description,
                          const std::string& name);

CLI::Validator positive(const std::string& unit);       // finite and > 0
CLI::Validator finite_number(const std::string& unit);  // any finite number
CLI::Validator int_range(int lo, int hi);               // an integer in [lo, hi]
// A finite number strictly between lo and hi; `what` names it ("an angle in degrees").
CLI::Validator open_interval(double lo, double hi, const std::string& what,
                             const std::string& name = "RANGE");
// Three comma-separated finite numbers (see parse_vec3); `what` names them ("vx,vy,vz in m/s").
CLI::Validator vec3(const std::string& what);
// A file name ending in one of `extensions` (with the dot: ".png"), not just the extension.
CLI::Validator file_extension(const std::vector<std::string>& extensions);

// ---------------------------------------------------------------- errors and exit status

// A bad argument found after parsing (an inconsistent combination, an unwritable file):
// the tools exit with status 2 on it, as CLI11 parse errors do.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Parses the command line (with --version added: the program's name and rsd's version).
// Returns the exit status when the tool should stop now: 0
// after --help, 2 on a parse error (CLI11 has printed the message); nullopt to go on.
std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv);

// Runs a tool's body, turning exceptions into "<tool>: error: ..." on stderr and the exit
// status: 2 for UsageError, 1 for any other std::exception.
int run_tool(const std::string& tool, const std::function<int()>& body);

// Throws UsageError unless `file` can be opened for writing (it is created if missing,
// never truncated), so a tool fails before its work rather than after.
void require_writable(const std::string& file, const std::string& option);

// ---------------------------------------------------------------- formatting

// Shortest form with `precision` significant digits ("0.7323", "1e-05"); inf, -inf, nan.
std::string format_number(double x, int precision = 4);
// `decimals` digits after the point ("879.19"); non-finite values as format_number.
std::string format_fixed(double x, int decimals);
// "(x, y, z)", each with format_number.
std::string format_vec3(const Eigen::Vector3d& v);
// A 3x3 matrix row by row, comma-separated, as --imu-to-camera takes it ("0,-1,0,-1,0,0,0,0,-1").
std::string matrix_text(const Eigen::Matrix3d& m);

// JSON number with 12 significant digits; null for inf and nan, which JSON lacks.
std::string json_number(double x);
// JSON array of three json_number.
std::string json_vec3(const Eigen::Vector3d& v);
// JSON string literal. Escapes only quotes and backslashes: the tools' strings are
// their own messages, which hold no control characters.
std::string json_string(const std::string& s);

}  // namespace rsd::tools
