#include "formats/number_text.hpp"

#include <cmath>
#include <cstdlib>

namespace rsd::formats {

std::optional<double> parse_number(const std::string& s) {
  if (s.empty()) return std::nullopt;
  char* end = nullptr;
  const double x = std::strtod(s.c_str(), &end);
  // strtod stops at the first bad character and overflows to inf: reject both.
  if (end != s.c_str() + s.size() || !std::isfinite(x)) return std::nullopt;
  return x;
}

}  // namespace rsd::formats
