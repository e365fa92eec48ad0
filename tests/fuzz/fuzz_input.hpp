// The fuzz targets' common ground. Each target is one LLVMFuzzerTestOneInput that runs an input
// through one of rsd's parsers; a documented error (ConfigError, RecordingError, a counted skip)
// is a correct answer, anything else (a crash, another exception, a sanitizer report, a hang)
// is a defect. Built two ways (tests/fuzz/CMakeLists.txt): with libFuzzer under clang to search
// (tests/fuzz/run.sh), and with replay_main.cpp in the normal build, where CTest runs every
// corpus file, crashes found earlier included, through it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace rsd::fuzz {

// The parsers read files: `data` written as `name` in a scratch directory of this process's
// (removed when it exits); returns the path.
std::string write_file(const std::string& name, const uint8_t* data, size_t size);
std::string write_file(const std::string& name, std::string_view text);

// The scratch directory itself (for targets that read a directory of files).
std::string scratch_dir();

// An input that stands for several files: its parts, separated by lines holding only "%%".
std::vector<std::string_view> split_parts(const uint8_t* data, size_t size);

// Writes the input's parts as the files `names` in the scratch directory (subdirectories made
// as needed; a part not given is an empty file); returns the directory.
std::string write_parts(const uint8_t* data, size_t size, const std::vector<std::string>& names);

}  // namespace rsd::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);
