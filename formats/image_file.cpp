#include "formats/image_file.hpp"

#include <png.h>

#include <cstdio>
#include <fstream>
#include <memory>
#include <stdexcept>

#include "dsp/core/pixel_conversion.hpp"

namespace rsd::formats {

namespace {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using File = std::unique_ptr<std::FILE, FileCloser>;

[[noreturn]] void fail(const std::string& path, const std::string& why) {
  throw std::runtime_error(path + ": " + why);
}

// A header's size against the documented limits, before the image is allocated.
void check_size(const std::string& path, long long w, long long h) {
  if (w > kMaxImageSide || h > kMaxImageSide || w * h > kMaxImagePixels)
    fail(path, "claims " + std::to_string(w) + "x" + std::to_string(h) + " pixels, beyond rsd's limit (sides up to " +
                   std::to_string(kMaxImageSide) + ", " + std::to_string(kMaxImagePixels) + " pixels in all)");
}

// The bytes left in a stream after its read position.
long long bytes_left(std::ifstream& in) {
  const auto here = in.tellg();
  in.seekg(0, std::ios::end);
  const auto end = in.tellg();
  in.seekg(here);
  return here < 0 || end < 0 ? 0 : static_cast<long long>(end - here);
}

bool has_suffix(const std::string& s, const std::string& suf) {
  return s.size() >= suf.size() && s.compare(s.size() - suf.size(), suf.size(), suf) == 0;
}

dsp::Image read_pgm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open for reading");
  std::string magic;
  in >> magic;
  if (magic != "P5") fail(path, "not a binary PGM (magic '" + magic + "', expected P5)");
  auto next_int = [&](const char* what) {
    in >> std::ws;
    while (in.peek() == '#') {  // comments may sit between header fields
      std::string line;
      std::getline(in, line);
      in >> std::ws;
    }
    long v = -1;
    if (!(in >> v) || v <= 0 || v > 65535) fail(path, std::string("bad PGM header field ") + what);
    return static_cast<int>(v);
  };
  const int w = next_int("width"), h = next_int("height"), maxval = next_int("maxval");
  in.get();  // the single whitespace byte before the raster
  check_size(path, w, h);
  const long long need = static_cast<long long>(w) * h * (maxval > 255 ? 2 : 1);
  if (bytes_left(in) < need)  // before allocating what the header claims
    fail(path, "truncated PGM raster: expected " + std::to_string(need) + " bytes, the file holds " +
                   std::to_string(bytes_left(in)));
  dsp::Image img(w, h, maxval > 255 ? dsp::PixelFormat::Mono16 : dsp::PixelFormat::Mono8);
  if (!in.read(reinterpret_cast<char*>(img.data.data()), static_cast<std::streamsize>(img.data.size())))
    fail(path, "truncated PGM raster: expected " + std::to_string(img.data.size()) + " bytes");
  if (img.format == dsp::PixelFormat::Mono16)  // PGM is big-endian; keep host order in memory
    for (size_t i = 0; i + 1 < img.data.size(); i += 2) std::swap(img.data[i], img.data[i + 1]);
  return img;
}

dsp::Image read_png(const std::string& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&png, path.c_str())) fail(path, std::string("not a readable PNG: ") + png.message);
  if (png.width > static_cast<png_uint_32>(kMaxImageSide) || png.height > static_cast<png_uint_32>(kMaxImageSide) ||
      static_cast<long long>(png.width) * png.height > kMaxImagePixels) {
    png_image_free(&png);
    check_size(path, png.width, png.height);
  }
  const bool grey = (png.format & PNG_FORMAT_FLAG_COLOR) == 0;
  const bool deep = (png.format & PNG_FORMAT_FLAG_LINEAR) != 0;
  dsp::Image img;
  if (grey && deep) {
    png.format = PNG_FORMAT_LINEAR_Y;
    img = dsp::Image(png.width, png.height, dsp::PixelFormat::Mono16);
  } else {
    png.format = grey ? PNG_FORMAT_GRAY : PNG_FORMAT_RGB;
    img = dsp::Image(png.width, png.height, grey ? dsp::PixelFormat::Mono8 : dsp::PixelFormat::Rgb8);
  }
  if (!png_image_finish_read(&png, nullptr, img.data.data(), 0, nullptr)) {
    const std::string msg = png.message;
    png_image_free(&png);
    fail(path, "PNG decoding failed: " + msg);
  }
  return img;
}

}  // namespace

void write_png(const std::string& path, const dsp::ImageView& img) {
  if (img.format != dsp::PixelFormat::Mono8 && img.format != dsp::PixelFormat::Mono16 && img.format != dsp::PixelFormat::Rgb8) {
    dsp::Image rgb(img.width, img.height, dsp::PixelFormat::Rgb8);  // YUV and mosaics: as they look
    dsp::convert_to_rgb(img, rgb.view());
    return write_png(path, rgb.view());
  }
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(img.width);
  png.height = static_cast<png_uint_32>(img.height);
  png.format = img.format == dsp::PixelFormat::Rgb8     ? PNG_FORMAT_RGB
               : img.format == dsp::PixelFormat::Mono16 ? PNG_FORMAT_LINEAR_Y
                                                        : PNG_FORMAT_GRAY;
  // The simplified API treats 16-bit data as linear; stride is given in components.
  const png_int_32 stride = static_cast<png_int_32>(img.stride / (img.format == dsp::PixelFormat::Mono16 ? 2 : 1));
  if (!png_image_write_to_file(&png, path.c_str(), 0, img.data, stride, nullptr))
    fail(path, std::string("cannot write PNG: ") + png.message);
}

dsp::Image read_image(const std::string& path) {
  if (has_suffix(path, ".pgm") || has_suffix(path, ".PGM")) return read_pgm(path);
  File f(std::fopen(path.c_str(), "rb"));
  if (!f) fail(path, "cannot open for reading");
  unsigned char sig[8] = {};
  const size_t n = std::fread(sig, 1, 8, f.get());
  if (n >= 2 && sig[0] == 'P' && sig[1] == '5') return read_pgm(path);
  if (n != 8 || png_sig_cmp(sig, 0, 8) != 0) fail(path, "neither PNG nor binary PGM");
  return read_png(path);
}

}  // namespace rsd::formats
