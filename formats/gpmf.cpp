#include "formats/gpmf.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace rsd::formats {

namespace {

// One key-length-value item: its header read, its data where it lies in the payload.
struct Klv {
  char key[5] = {};
  char type = 0;
  std::size_t struct_size = 0, repeat = 0;
  std::size_t offset = 0;  // of the header, from the payload's start
  const std::uint8_t* data = nullptr;
  bool is(const char* k) const { return std::memcmp(key, k, 4) == 0; }
  std::size_t bytes() const { return struct_size * repeat; }
};

std::size_t type_size(char type) {
  switch (type) {
    case 'b': case 'B': case 'c': return 1;
    case 's': case 'S': return 2;
    case 'l': case 'L': case 'f': case 'q': case 'F': return 4;
    case 'd': case 'j': case 'J': case 'Q': return 8;
    default: return 0;  // nested, complex ('?'), GUIDs, dates: not numbers
  }
}

std::uint64_t big_endian_unsigned(const std::uint8_t* p, std::size_t n) {
  std::uint64_t v = 0;
  for (std::size_t i = 0; i < n; ++i) v = v << 8 | p[i];
  return v;
}

class PayloadReader {
 public:
  PayloadReader(const std::uint8_t* data, std::size_t size, const std::string& what) : base_(data), size_(size), what_(what) {}

  std::vector<GpmfGyro> gyro_streams() {
    std::vector<GpmfGyro> out;
    items(0, size_, [&](const Klv& devc) {
      if (devc.is("DEVC") && devc.type == 0) device(devc, out);
    });
    return out;
  }

 private:
  [[noreturn]] void fail(std::size_t offset, const char* key, const std::string& why) const {
    throw std::runtime_error(what_ + ": byte " + std::to_string(offset) + (key && *key ? std::string(": '") + key + "'" : "") +
                             " " + why);
  }

  // Calls f for every item in [begin, end); an all-zero header ends the list (the padding some
  // writers leave after the last item).
  template <class F>
  void items(std::size_t begin, std::size_t end, F f) const {
    for (std::size_t at = begin; at < end;) {
      if (end - at < 8) fail(at, "", "is a truncated item header (" + std::to_string(end - at) + " bytes left, 8 needed)");
      const std::uint8_t* h = base_ + at;
      if (big_endian_unsigned(h, 8) == 0) return;
      Klv k;
      std::memcpy(k.key, h, 4);
      for (int i = 0; i < 4; ++i)
        if (h[i] < 0x20 || h[i] > 0x7e) fail(at, "", "is not a GPMF key (bytes that are not printable ASCII)");
      k.type = static_cast<char>(h[4]);
      k.struct_size = h[5];
      k.repeat = static_cast<std::size_t>(big_endian_unsigned(h + 6, 2));
      k.offset = at;
      k.data = h + 8;
      const std::size_t padded = (k.bytes() + 3) & ~std::size_t{3};
      if (padded > end - at - 8)
        fail(at, k.key, "holds " + std::to_string(k.bytes()) + " bytes but only " + std::to_string(end - at - 8) +
                            " remain in its container");
      f(k);
      at += 8 + padded;
    }
  }

  // Element i of a numeric item, as a double.
  double number(const Klv& k, std::size_t i) const {
    const std::size_t n = type_size(k.type);
    const std::uint64_t raw = big_endian_unsigned(k.data + i * n, n);
    switch (k.type) {
      case 'b': return static_cast<std::int8_t>(raw);
      case 'B': return static_cast<double>(raw);
      case 's': return static_cast<std::int16_t>(raw);
      case 'S': return static_cast<double>(raw);
      case 'l': return static_cast<std::int32_t>(raw);
      case 'L': return static_cast<double>(raw);
      case 'j': return static_cast<double>(static_cast<std::int64_t>(raw));
      case 'J': return static_cast<double>(raw);
      case 'q': return static_cast<std::int32_t>(raw) / 65536.0;
      case 'Q': return static_cast<double>(static_cast<std::int64_t>(raw)) / 4294967296.0;
      case 'f': {
        const auto bits = static_cast<std::uint32_t>(raw);
        float v;
        std::memcpy(&v, &bits, 4);
        return v;
      }
      case 'd': {
        double v;
        std::memcpy(&v, &raw, 8);
        return v;
      }
      default: fail(k.offset, k.key, std::string("is of type '") + k.type + "', not a number");
    }
  }

  std::vector<double> numbers(const Klv& k) const {
    const std::size_t n = type_size(k.type);
    if (n == 0 || k.type == 'c' || k.type == 'F') fail(k.offset, k.key, std::string("is of type '") + k.type + "', not a number");
    if (k.struct_size % n != 0) fail(k.offset, k.key, "has a structure size that is not a whole number of its type's values");
    std::vector<double> v(k.bytes() / n);
    for (std::size_t i = 0; i < v.size(); ++i) v[i] = number(k, i);
    return v;
  }

  double first_number(const Klv& k) const {
    const std::vector<double> v = numbers(k);
    if (v.empty()) fail(k.offset, k.key, "holds no value");
    return v.front();
  }

  // A count or a time stamp: a whole number in [0, limit], as a converted integer must be (a
  // damaged payload can hold any double here).
  double whole_number(const Klv& k, double limit) const {
    const double x = first_number(k);
    if (!(x >= 0 && x <= limit) || x != std::floor(x))
      fail(k.offset, k.key, "holds " + std::to_string(x) + ": not a whole number from 0 to " + std::to_string(limit));
    return x;
  }

  static std::string text(const Klv& k) {
    std::string s(reinterpret_cast<const char*>(k.data), k.bytes());
    return s.substr(0, s.find('\0'));
  }

  void device(const Klv& devc, std::vector<GpmfGyro>& out) const {
    std::string name;
    items(devc.offset + 8, devc.offset + 8 + devc.bytes(), [&](const Klv& k) {
      if (k.is("DVNM") && k.type == 'c') name = text(k);
      if (k.is("STRM") && k.type == 0) stream(k, name, out);
    });
  }

  // A stream's sticky keys (SCAL, ORIN, SIUN, STMP, TSMP) come before its samples.
  void stream(const Klv& strm, const std::string& device, std::vector<GpmfGyro>& out) const {
    GpmfGyro g;
    g.device = device;
    std::vector<double> scal;
    bool has_gyro = false;
    items(strm.offset + 8, strm.offset + 8 + strm.bytes(), [&](const Klv& k) {
      if (k.is("SCAL")) scal = numbers(k);
      else if (k.is("ORIN") && k.type == 'c') g.orin = text(k);
      else if (k.is("SIUN") && k.type == 'c') g.siun = text(k);
      else if (k.is("STMP")) g.stmp_us = static_cast<std::uint64_t>(whole_number(k, 0x1p63));
      else if (k.is("TSMP")) g.tsmp = static_cast<std::uint32_t>(whole_number(k, 4294967295.0));
      else if (k.is("GYRO")) {
        has_gyro = true;
        gyro(k, scal, g);
      }
    });
    if (has_gyro) out.push_back(std::move(g));
  }

  void gyro(const Klv& k, const std::vector<double>& scal, GpmfGyro& g) const {
    const std::size_t n = type_size(k.type);
    if (n == 0 || k.struct_size != 3 * n)
      fail(k.offset, k.key, "samples are " + std::to_string(k.struct_size) + " bytes of type '" + std::string(1, k.type) +
                                "': a gyro sample is three axes");
    if (scal.size() != 1 && scal.size() != 3)
      fail(k.offset, k.key, "has no SCAL before it (one divisor, or one per axis), or " + std::to_string(scal.size()) + " of them");
    for (double s : scal)
      if (!(s != 0 && std::isfinite(s))) fail(k.offset, k.key, "has a SCAL of " + std::to_string(s) + ": a divisor must be finite and not 0");
    const std::vector<double> v = numbers(k);
    for (std::size_t i = 0; i + 2 < v.size(); i += 3) {
      Eigen::Vector3d w;
      for (int a = 0; a < 3; ++a) w[a] = v[i + a] / scal[scal.size() == 3 ? a : 0];
      if (!w.allFinite()) fail(k.offset, k.key, "sample " + std::to_string(i / 3) + " is not a finite number");
      g.rate_rad_s.push_back(w);
    }
  }

  const std::uint8_t* base_;
  std::size_t size_;
  const std::string& what_;
};

}  // namespace

std::vector<GpmfGyro> read_gpmf_gyro(const std::uint8_t* data, std::size_t size, const std::string& what) {
  return PayloadReader(data, size, what).gyro_streams();
}

}  // namespace rsd::formats
