// The message of the exception a call throws, or "" when it throws none: for tests that check
// an error names its file, line, key or column.
#pragma once

#include <exception>
#include <functional>
#include <string>

namespace rsd::test {

inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

}  // namespace rsd::test
