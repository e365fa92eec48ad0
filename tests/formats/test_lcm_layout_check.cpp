// Every LCM type in lcmtypes/ (today's and any added later: the list is generated) decodes only
// after every string and array length has been checked against the payload.
//
// For each type a payload is built from the generated layout alone (every array two long, every
// string "ab"); lcm-gen's own decoder must read it whole and encode it back byte for byte (the
// layout and the decoder agree), then every length in it is replaced by -1, INT_MIN, 0 (a
// string's), one past what is left and INT_MAX, and the payload is cut at every byte: each must
// be refused, none may throw, crash or allocate what the length claims (ASan watches).
#include <gtest/gtest.h>

#include <climits>
#include <cstdint>
#include <string>
#include <tuple>
#include <vector>

#include "formats/image_t_codec.hpp"
#include "formats/lcm_layout_check.hpp"

using namespace rsd::formats;
using lcm_layout::Kind;
using lcm_layout::kTypes;

namespace {

void put(std::vector<uint8_t>& out, int64_t v, int size) {
  for (int i = size - 1; i >= 0; --i) out.push_back(static_cast<uint8_t>(static_cast<uint64_t>(v) >> (8 * i)));
}

// The fields of kTypes[t] as the layout says they are encoded; integer members that size an
// array hold 2, so each such array has elements to check.
void encode_sample(int t, std::vector<uint8_t>& out) {
  const lcm_layout::Type& ty = kTypes[static_cast<size_t>(t)];
  std::vector<int64_t> ints(static_cast<size_t>(ty.nfields), 0);
  for (int i = 0; i < ty.nfields; ++i) {
    const lcm_layout::Field& f = ty.fields[static_cast<size_t>(i)];
    int64_t count = 1;
    for (int d = 0; d < f.ndims; ++d)
      count *= f.dims[static_cast<size_t>(d)].member >= 0 ? ints[static_cast<size_t>(f.dims[static_cast<size_t>(d)].member)]
                                                          : f.dims[static_cast<size_t>(d)].fixed;
    for (int64_t k = 0; k < count; ++k) {
      if (f.kind == Kind::String) {
        put(out, 3, 4);
        out.insert(out.end(), {'a', 'b', 0});
      } else if (f.kind == Kind::Struct) {
        encode_sample(f.nested, out);
      } else if (f.integer && f.ndims == 0) {
        ints[static_cast<size_t>(i)] = 2;
        put(out, 2, f.size);
      } else {
        for (int b = 0; b < f.size; ++b) out.push_back(f.size == 1 ? 1 : 0);  // booleans 1; 0.0 and zeros
      }
    }
  }
}

template <class Msg>
std::vector<uint8_t> sample_payload() {
  std::vector<uint8_t> out;
  put(out, Msg::getHash(), 8);
  encode_sample(lcm_layout::kIndex<Msg>, out);
  return out;
}

template <class Msg>
void check_type() {
  SCOPED_TRACE(Msg::getTypeName());
  const std::vector<uint8_t> good = sample_payload<Msg>();
  std::string why;
  std::vector<LengthAt> lengths;
  ASSERT_EQ(check_layout<Msg>(good.data(), good.size(), why, &lengths), LayoutStatus::Fits) << why;
  // lcm-gen's decoder reads the same bytes whole, and writes them back.
  Msg m;
  ASSERT_EQ(m.decode(good.data(), 0, static_cast<int>(good.size())), static_cast<int>(good.size()));
  std::vector<uint8_t> again(static_cast<size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(again.data(), 0, static_cast<int>(again.size())), static_cast<int>(again.size()));
  EXPECT_EQ(again, good);
  ASSERT_EQ(decode_checked(good.data(), good.size(), m, why), DecodeStatus::Ok) << why;

  for (const LengthAt& l : lengths) {
    const int64_t left = static_cast<int64_t>(good.size() - l.offset) - l.size;
    std::vector<int64_t> bad = {-1, INT_MIN, left + 1, INT_MAX};
    if (l.string) bad.push_back(0);  // a string's length counts its terminating zero
    for (const int64_t v : bad) {
      if (l.size < 8 && (v < -(int64_t{1} << (8 * l.size - 1)) || v >= (int64_t{1} << (8 * l.size - 1)))) continue;
      std::vector<uint8_t> p = good;
      std::vector<uint8_t> bytes;
      put(bytes, v, l.size);
      std::copy(bytes.begin(), bytes.end(), p.begin() + static_cast<std::ptrdiff_t>(l.offset));
      Msg out;
      DecodeStatus st = DecodeStatus::Ok;
      EXPECT_NO_THROW(st = decode_checked(p.data(), p.size(), out, why)) << l.field << " = " << v;
      EXPECT_NE(st, DecodeStatus::Ok) << l.field << " = " << v;
      EXPECT_NE(why.find(l.field.substr(l.field.rfind('.') + 1)), std::string::npos) << why;  // names the field
    }
  }
  for (size_t cut = 0; cut < good.size(); ++cut) {
    Msg out;
    EXPECT_NE(decode_checked(good.data(), cut, out, why), DecodeStatus::Ok) << "cut at " << cut;
  }
}

}  // namespace

TEST(LcmLayoutCheck, EveryLengthOfEveryTypeIsCheckedBeforeDecoding) {
  ASSERT_EQ(std::tuple_size_v<lcm_layout::AllMessages>, kTypes.size());
  std::apply([](auto... msgs) { (check_type<decltype(msgs)>(), ...); }, lcm_layout::AllMessages{});
}

// The types with variable lengths have them all found: strings of every type, image_t's size,
// metadata count and its entries' keys and value lengths.
TEST(LcmLayoutCheck, TheWalkFindsEveryVariableLength) {
  std::string why;
  std::vector<LengthAt> lengths;
  const std::vector<uint8_t> img = sample_payload<bot_core::image_t>();
  ASSERT_EQ(check_layout<bot_core::image_t>(img.data(), img.size(), why, &lengths), LayoutStatus::Fits) << why;
  std::vector<std::string> names;
  for (const LengthAt& l : lengths) names.push_back(l.field);
  const std::vector<std::string> want = {"bot_core.image_t.size",         "bot_core.image_t.nmetadata",
                                         "bot_core.image_metadata_t.key", "bot_core.image_metadata_t.n",
                                         "bot_core.image_metadata_t.key", "bot_core.image_metadata_t.n"};
  EXPECT_EQ(names, want);
  lengths.clear();
  const std::vector<uint8_t> info = sample_payload<rsd::frame_info_t>();
  ASSERT_EQ(check_layout<rsd::frame_info_t>(info.data(), info.size(), why, &lengths), LayoutStatus::Fits);
  int strings = 0;
  for (const LengthAt& l : lengths) strings += l.string;
  EXPECT_EQ(strings, 2);  // unrectified_reason and calibration (the one fuzzing found unchecked)
}
