// Numbers as rsd-recording/1 writes them, internal to its writer (recording_v1_write.cpp) and
// its reader (recording_v1.cpp: a target's numbers back into the command line's text, a bad
// quaternion's norm).
#pragma once

#include <charconv>
#include <string>

namespace rsd::formats::recording_v1_detail {

inline std::string num(double v) {  // shortest text that reads back to the same double
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

}  // namespace rsd::formats::recording_v1_detail
