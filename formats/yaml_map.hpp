// Strict reading of YAML configuration: every key must be known, every value of the right
// type and range; errors name the file, line, column and the key's dotted path.
#pragma once

#include <yaml-cpp/yaml.h>

#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace rsd::formats {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A view of one YAML mapping. Reading a key marks it known; finish() rejects the rest.
class YamlMap {
 public:
  YamlMap(std::string file, YAML::Node node, std::string path);
  static YamlMap load(const std::string& file);  // the document's root mapping

  bool has(const std::string& key) const { return static_cast<bool>(node_[key]); }
  // Present and null (JSON's null, YAML's ~): "not given" in formats that write every key.
  bool is_null(const std::string& key) const { return has(key) && node_[key].IsNull(); }
  double number(const std::string& key, double fallback);
  double number(const std::string& key);  // required
  int integer(const std::string& key, int fallback);
  bool boolean(const std::string& key, bool fallback);
  std::string text(const std::string& key, const std::string& fallback);
  std::vector<double> numbers(const std::string& key, size_t n);  // required length n, finite
  // A list of `rows` lists of `cols` finite numbers, row-major (required).
  std::vector<double> matrix(const std::string& key, size_t rows, size_t cols);
  YamlMap map(const std::string& key);  // nested mapping (required)
  std::vector<std::string> keys() const;
  const std::string& file() const { return file_; }

  // Throws for any key not read; call after reading everything.
  void finish() const;
  [[noreturn]] void fail(const std::string& key, const std::string& why) const;
  std::string path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

 private:
  YAML::Node child(const std::string& key);
  std::string where(const YAML::Node& n) const;
  std::string key_name(const YAML::Node& key) const;
  std::string file_;
  YAML::Node node_;
  std::string path_;
  std::set<std::string> used_;
};

}  // namespace rsd::formats
