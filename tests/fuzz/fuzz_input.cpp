#include "tests/fuzz/fuzz_input.hpp"

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <system_error>

namespace rsd::fuzz {

namespace {

struct Scratch {
  std::filesystem::path dir = std::filesystem::temp_directory_path() / ("rsd-fuzz-" + std::to_string(getpid()));
  Scratch() { std::filesystem::create_directories(dir); }
  ~Scratch() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
};

Scratch& scratch() {
  static Scratch s;
  return s;
}

}  // namespace

std::string scratch_dir() { return scratch().dir.string(); }

std::string write_file(const std::string& name, const uint8_t* data, size_t size) {
  const std::filesystem::path file = scratch().dir / name;
  std::filesystem::create_directories(file.parent_path());
  const std::string path = file.string();
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

std::string write_file(const std::string& name, std::string_view text) {
  return write_file(name, reinterpret_cast<const uint8_t*>(text.data()), text.size());
}

std::vector<std::string_view> split_parts(const uint8_t* data, size_t size) {
  const std::string_view all(reinterpret_cast<const char*>(data), size);
  std::vector<std::string_view> parts;
  size_t start = 0;
  for (;;) {
    const size_t at = all.find("\n%%\n", start);
    if (at == std::string_view::npos) break;
    parts.push_back(all.substr(start, at + 1 - start));
    start = at + 4;
  }
  parts.push_back(all.substr(start));
  return parts;
}

std::string write_parts(const uint8_t* data, size_t size, const std::vector<std::string>& names) {
  const auto parts = split_parts(data, size);
  for (size_t i = 0; i < names.size(); ++i) write_file(names[i], i < parts.size() ? parts[i] : "");
  return scratch_dir();
}

}  // namespace rsd::fuzz
