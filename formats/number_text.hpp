// Numbers in text (command lines, CSV fields, LCM metadata, target names): the whole text
// must be one finite number, or there is none.
#pragma once

#include <optional>
#include <string>

namespace rsd::formats {

std::optional<double> parse_number(const std::string& s);

}  // namespace rsd::formats
