// Numbers in text (command lines, CSV fields, LCM metadata, target names): the whole text
// must be one finite number, or there is none; and a double written back as text.
#pragma once

#include <optional>
#include <string>

namespace rsd::formats {

std::optional<double> parse_number(const std::string& s);

// The shortest text that reads back to the same double ("0.002", "30", "1e-05"): how every file
// and message rsd writes states a number.
std::string number_text(double x);

}  // namespace rsd::formats
