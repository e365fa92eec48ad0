// PNG and PGM files: what the writer writes reads back pixel for pixel, and a header that
// claims more than rsd's documented limit (or more than the file holds) is refused before the
// image is allocated (issue 16, defect 4: a 67-byte PNG claiming 100000x100000 took 3 GB).
#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "formats/image_file.hpp"
#include "tests/support/temp_dir.hpp"

namespace rsd::formats::test_image_file {  // shares a unity unit (tests/CMakeLists.txt)
namespace {

const test::TempDir& g_tmp = test::register_temp_dir("rsd_test_image_file_");

void put_be32(std::vector<uint8_t>& out, uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) out.push_back(static_cast<uint8_t>(v >> s));
}

// One PNG chunk: length, type, data, CRC over type and data (PNG spec, section 5.3).
void chunk(std::vector<uint8_t>& out, const char* type, const std::vector<uint8_t>& data) {
  put_be32(out, static_cast<uint32_t>(data.size()));
  std::vector<uint8_t> typed(type, type + 4);
  typed.insert(typed.end(), data.begin(), data.end());
  out.insert(out.end(), typed.begin(), typed.end());
  put_be32(out, static_cast<uint32_t>(crc32(0, typed.data(), static_cast<uInt>(typed.size()))));
}

// A valid PNG header claiming w x h 8-bit grey pixels, with an empty IDAT: tiny on disk.
std::string tiny_png_claiming(uint32_t w, uint32_t h) {
  std::vector<uint8_t> png = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  std::vector<uint8_t> ihdr;
  put_be32(ihdr, w);
  put_be32(ihdr, h);
  ihdr.insert(ihdr.end(), {8, 0, 0, 0, 0});  // depth 8, grey, deflate, adaptive, no interlace
  chunk(png, "IHDR", ihdr);
  chunk(png, "IDAT", {});
  chunk(png, "IEND", {});
  const std::string path = g_tmp.path("claims_" + std::to_string(w) + "x" + std::to_string(h) + ".png");
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  return path;
}

std::string error_reading(const std::string& path) {
  try {
    read_image(path);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

TEST(ImageFile, WrittenPngReadsBackPixelForPixel) {
  for (const dsp::PixelFormat f : {dsp::PixelFormat::Mono8, dsp::PixelFormat::Mono16, dsp::PixelFormat::Rgb8}) {
    dsp::Image img(37, 11, f);
    for (size_t i = 0; i < img.data.size(); ++i) img.data[i] = static_cast<uint8_t>(i * 7 + 3);
    const std::string path = g_tmp.path("round_trip.png");
    write_png(path, img.view());
    const dsp::Image back = read_image(path);
    EXPECT_EQ(back.width, 37);
    EXPECT_EQ(back.height, 11);
    EXPECT_EQ(back.format, f);
    EXPECT_EQ(back.data, img.data);
  }
}

TEST(ImageFile, APngClaimingTooManyPixelsIsRefusedBeforeAllocating) {
  const std::string huge = tiny_png_claiming(100000, 100000);
  const std::string wide = tiny_png_claiming(16385, 1);
  const std::string many = tiny_png_claiming(16384, 8193);  // both sides allowed, the product not
  const std::string e = error_reading(huge);
  EXPECT_NE(e.find("claims_100000x100000.png: claims 100000x100000 pixels, beyond rsd's limit"), std::string::npos) << e;
  EXPECT_NE(error_reading(wide).find("beyond rsd's limit"), std::string::npos) << error_reading(wide);
  EXPECT_NE(error_reading(many).find("beyond rsd's limit"), std::string::npos) << error_reading(many);
  // At the limit the header is accepted and the (empty) image data is what fails.
  const std::string ok = error_reading(tiny_png_claiming(64, 64));
  EXPECT_EQ(ok.find("beyond rsd's limit"), std::string::npos) << ok;
  EXPECT_NE(ok, "no error");
}

TEST(ImageFile, APgmClaimingMoreThanTheFileHoldsIsRefusedBeforeAllocating) {
  const std::string path = g_tmp.path("short.pgm");
  std::ofstream(path, std::ios::binary) << "P5\n# a comment\n8000 8000\n65535\n" << std::string(10, 'x');
  // A reader that allocated first would fail later with "expected ... bytes" alone.
  const std::string e = error_reading(path);
  EXPECT_NE(e.find("short.pgm: truncated PGM raster: expected 128000000 bytes, the file holds 10"), std::string::npos) << e;
  const std::string big = g_tmp.path("big.pgm");
  std::ofstream(big, std::ios::binary) << "P5 20000 2 255\n" << std::string(40000, 'x');
  EXPECT_NE(error_reading(big).find("claims 20000x2 pixels, beyond rsd's limit"), std::string::npos) << error_reading(big);
}

TEST(ImageFile, AWholePgmReadsBackWithItsByteOrder) {
  const std::string path = g_tmp.path("deep.pgm");
  std::ofstream(path, std::ios::binary) << "P5 2 1 65535\n" << std::string("\x01\x02\x03\x04", 4);
  const dsp::Image img = read_image(path);
  ASSERT_EQ(img.format, dsp::PixelFormat::Mono16);
  const uint16_t* px = reinterpret_cast<const uint16_t*>(img.data.data());
  EXPECT_EQ(px[0], 0x0102);
  EXPECT_EQ(px[1], 0x0304);
}

}  // namespace
}  // namespace rsd::formats::test_image_file
