// The one check of an LCM payload's variable lengths before lcm-gen's decoder reads it: every
// string length 1..(bytes left), every array dimension 0..(what the bytes left can hold), walked
// from the types' layout that lcmtypes/lcm_layout.py generates from the same .lcm files as the
// decoders, so that a type or field added later is checked without anyone remembering to.
//
// Why: lcm-gen's C++ decoders check a string's length against the payload's end but not its sign
// (a length of INT_MIN overflows, -1 reaches std::string::assign as a huge size) and resize an
// array to whatever its dimension says before reading it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "rsd_lcm_layout.hpp"

namespace rsd::formats {

enum class LayoutStatus { Fits, Truncated, BadLength };

// A length in a payload: a string's, or an integer member that sizes an array (met where the
// array is).
struct LengthAt {
  size_t offset = 0;  // of its 4 (string) or size-of-member bytes, from the payload's start
  int size = 4;       // bytes of the length (big-endian, signed)
  bool string = false;
  std::string field;  // "type.member"
  int64_t value = 0;
};

// Walks `data` (n bytes: an 8-byte fingerprint, then the fields) as kTypes[type]. `why` names
// the field that does not fit; `lengths`, if given, receives every length met on the way.
LayoutStatus check_layout(int type, const uint8_t* data, size_t n, std::string& why,
                          std::vector<LengthAt>* lengths = nullptr);

template <class Msg>
LayoutStatus check_layout(const uint8_t* data, size_t n, std::string& why, std::vector<LengthAt>* lengths = nullptr) {
  static_assert(lcm_layout::kIndex<Msg> >= 0, "a type not in lcmtypes/");
  return check_layout(lcm_layout::kIndex<Msg>, data, n, why, lengths);
}

}  // namespace rsd::formats
