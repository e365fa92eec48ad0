// A scratch directory per test process (under the system temp dir, named by a prefix and the
// process id), removed with everything in it when the process ends.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace rsd::test {

class TempDir : public ::testing::Environment {
 public:
  explicit TempDir(const std::string& prefix)
      : dir_(std::filesystem::temp_directory_path() / (prefix + std::to_string(getpid()))) {}
  const std::filesystem::path& dir() const { return dir_; }
  // A path for `name` inside the directory (created on first use).
  std::string path(const std::string& name) const {
    std::filesystem::create_directories(dir_);
    return (dir_ / name).string();
  }
  // A file `name` in the directory holding `text`; its path.
  std::string file_with(const std::string& name, const std::string& text) const {
    const std::string p = path(name);
    std::ofstream(p) << text;
    return p;
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }

 private:
  std::filesystem::path dir_;
};

// Registers a TempDir with GoogleTest (which owns it) and returns it.
inline TempDir& register_temp_dir(const std::string& prefix) {
  auto* t = new TempDir(prefix);
  ::testing::AddGlobalTestEnvironment(t);
  return *t;
}

}  // namespace rsd::test
