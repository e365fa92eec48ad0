#include "formats/lcm_layout_check.hpp"

#include <array>
#include <tuple>

namespace rsd::formats {

namespace {

using lcm_layout::Field;
using lcm_layout::Kind;
using lcm_layout::kTypes;
using lcm_layout::Type;

// Nested structs deeper than this are refused (the types here nest two deep).
constexpr int kMaxDepth = 8;

int64_t big_endian_signed(const uint8_t* p, int size) {
  uint64_t v = 0;
  for (int i = 0; i < size; ++i) v = v << 8 | p[i];
  if (size < 8 && (v >> (8 * size - 1)) & 1) v |= ~uint64_t{0} << (8 * size);  // sign-extend
  return static_cast<int64_t>(v);
}

// One walk over a payload: the position, and what went wrong where.
class Walk {
 public:
  Walk(const uint8_t* data, size_t n, std::string& why, std::vector<LengthAt>* lengths)
      : data_(data), n_(n), why_(why), lengths_(lengths) {}

  LayoutStatus type(int t, int depth) {
    if (depth > kMaxDepth) return fail(LayoutStatus::BadLength, kTypes[t].name, "nested too deep");
    const Type& ty = kTypes[static_cast<size_t>(t)];
    constexpr size_t kMax = std::tuple_size_v<decltype(Type::fields)>;
    std::array<int64_t, kMax> ints{};  // integer members met so far: their values and offsets
    std::array<size_t, kMax> at{};
    for (int i = 0; i < ty.nfields; ++i) {
      const Field& f = ty.fields[static_cast<size_t>(i)];
      int64_t count = 1;
      for (int d = 0; d < f.ndims; ++d) {
        const lcm_layout::Dim& dim = f.dims[static_cast<size_t>(d)];
        int64_t v = dim.fixed;
        std::string named;
        if (dim.member >= 0) {
          const Field& m = ty.fields[static_cast<size_t>(dim.member)];
          v = ints[static_cast<size_t>(dim.member)];
          named = std::string(" (") + m.name + " = " + std::to_string(v) + ")";
          if (lengths_) lengths_->push_back({at[static_cast<size_t>(dim.member)], m.size, false, std::string(ty.name) + "." + m.name, v});
        }
        if (v < 0) return fail(LayoutStatus::BadLength, ty.name, f.name, "has a negative length" + named);
        // Every element takes at least one byte: more elements than bytes left cannot fit.
        if (v > 0 && count > static_cast<int64_t>(left()) / v)
          return fail(LayoutStatus::BadLength, ty.name, f.name, "has more elements than the payload has bytes" + named);
        count *= v;
      }
      at[static_cast<size_t>(i)] = pos;
      const LayoutStatus st = field(ty, f, count, depth, ints[static_cast<size_t>(i)]);
      if (st != LayoutStatus::Fits) return st;
    }
    return LayoutStatus::Fits;
  }

  size_t pos = 8;  // after the fingerprint

 private:
  size_t left() const { return n_ - pos; }

  LayoutStatus field(const Type& ty, const Field& f, int64_t count, int depth, int64_t& value) {
    switch (f.kind) {
      case Kind::Primitive: return primitive(ty, f, count, value);
      case Kind::String:
        for (int64_t k = 0; k < count; ++k)
          if (const LayoutStatus st = string(ty, f); st != LayoutStatus::Fits) return st;
        return LayoutStatus::Fits;
      case Kind::Struct:
        for (int64_t k = 0; k < count; ++k)
          if (const LayoutStatus st = type(f.nested, depth + 1); st != LayoutStatus::Fits) return st;
        return LayoutStatus::Fits;
    }
    return LayoutStatus::BadLength;
  }

  LayoutStatus primitive(const Type& ty, const Field& f, int64_t count, int64_t& value) {
    const size_t bytes = static_cast<size_t>(count) * static_cast<size_t>(f.size);  // count <= left(): no overflow
    if (bytes > left()) return fail(LayoutStatus::Truncated, ty.name, f.name, "ends the payload early");
    if (f.integer && f.ndims == 0) value = big_endian_signed(data_ + pos, f.size);
    pos += bytes;
    return LayoutStatus::Fits;
  }

  // An LCM string: a 4-byte length counting its terminating NUL, then that many bytes.
  LayoutStatus string(const Type& ty, const Field& f) {
    if (left() < 4) return fail(LayoutStatus::Truncated, ty.name, f.name, "ends the payload early");
    const int64_t len = big_endian_signed(data_ + pos, 4);
    if (lengths_) lengths_->push_back({pos, 4, true, std::string(ty.name) + "." + f.name, len});
    pos += 4;
    if (len < 1 || static_cast<uint64_t>(len) > left())
      return fail(LayoutStatus::BadLength, ty.name, f.name,
                  "has a string length of " + std::to_string(len) + " with " + std::to_string(left()) + " bytes left");
    pos += static_cast<size_t>(len);
    return LayoutStatus::Fits;
  }

  LayoutStatus fail(LayoutStatus st, const char* type, const char* field, const std::string& what = "") {
    why_ = std::string(type) + "." + field + (what.empty() ? "" : " " + what);
    return st;
  }

  const uint8_t* data_;
  size_t n_;
  std::string& why_;
  std::vector<LengthAt>* lengths_;
};

}  // namespace

LayoutStatus check_layout(int type, const uint8_t* data, size_t n, std::string& why, std::vector<LengthAt>* lengths) {
  if (type < 0 || static_cast<size_t>(type) >= kTypes.size()) {
    why = "no such LCM type";
    return LayoutStatus::BadLength;
  }
  if (n < 8) {
    why = std::string(kTypes[static_cast<size_t>(type)].name) + " payload of " + std::to_string(n) +
          " bytes is shorter than a fingerprint";
    return LayoutStatus::Truncated;
  }
  Walk w(data, n, why, lengths);
  return w.type(type, 0);
}

}  // namespace rsd::formats
