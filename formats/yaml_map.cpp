#include "formats/yaml_map.hpp"

#include <cmath>

namespace rsd::formats {

YamlMap::YamlMap(std::string file, YAML::Node node, std::string path)
    : file_(std::move(file)), node_(std::move(node)), path_(std::move(path)) {
  if (!node_.IsMap()) throw ConfigError(where(node_) + ": '" + (path_.empty() ? "document" : path_) + "' must be a mapping");
}

YamlMap YamlMap::load(const std::string& file) {
  try {
    return YamlMap(file, YAML::LoadFile(file), "");
  } catch (const YAML::BadFile&) {
    throw ConfigError(file + ": cannot open");
  } catch (const YAML::ParserException& e) {
    throw ConfigError(file + ":" + std::to_string(e.mark.line + 1) + ":" + std::to_string(e.mark.column + 1) + ": " + e.msg);
  }
}

std::string YamlMap::where(const YAML::Node& n) const {
  const auto m = n.Mark();
  if (m.line < 0) return file_;
  return file_ + ":" + std::to_string(m.line + 1) + ":" + std::to_string(m.column + 1);
}

void YamlMap::fail(const std::string& key, const std::string& why) const {
  const YAML::Node n = node_[key];
  throw ConfigError(where(n ? n : node_) + ": '" + path(key) + "' " + why);
}

YAML::Node YamlMap::child(const std::string& key) {
  used_.insert(key);
  return node_[key];
}

double YamlMap::number(const std::string& key) {
  const YAML::Node n = child(key);
  if (!n) fail(key, "is missing");
  try {
    const double v = n.as<double>();
    if (!std::isfinite(v)) fail(key, "must be a finite number");
    return v;
  } catch (const YAML::Exception&) {
    fail(key, "must be a number, not '" + YAML::Dump(n) + "'");
  }
}

double YamlMap::number(const std::string& key, double fallback) { return has(key) ? number(key) : (used_.insert(key), fallback); }

int YamlMap::integer(const std::string& key, int fallback) {
  const YAML::Node n = child(key);
  if (!n) return fallback;
  try {
    return n.as<int>();
  } catch (const YAML::Exception&) {
    fail(key, "must be an integer, not '" + YAML::Dump(n) + "'");
  }
}

bool YamlMap::boolean(const std::string& key, bool fallback) {
  const YAML::Node n = child(key);
  if (!n) return fallback;
  try {
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    fail(key, "must be true or false, not '" + YAML::Dump(n) + "'");
  }
}

std::string YamlMap::text(const std::string& key, const std::string& fallback) {
  const YAML::Node n = child(key);
  if (!n) return fallback;
  if (!n.IsScalar()) fail(key, "must be a single value");
  return n.as<std::string>();
}

std::vector<double> YamlMap::numbers(const std::string& key, size_t count) {
  const YAML::Node n = child(key);
  if (!n) fail(key, "is missing");
  std::vector<double> v;
  try {
    v = n.as<std::vector<double>>();
  } catch (const YAML::Exception&) {
    fail(key, "must be a list of " + std::to_string(count) + " numbers");
  }
  if (v.size() != count) fail(key, "must have " + std::to_string(count) + " numbers, has " + std::to_string(v.size()));
  for (double x : v)
    if (!std::isfinite(x)) fail(key, "must hold finite numbers");
  return v;
}

std::vector<double> YamlMap::matrix(const std::string& key, size_t rows, size_t cols) {
  const YAML::Node n = child(key);
  if (!n) fail(key, "is missing");
  const std::string shape = "must be " + std::to_string(rows) + " rows of " + std::to_string(cols) + " numbers";
  if (!n.IsSequence() || n.size() != rows) fail(key, shape);
  std::vector<double> v;
  for (const auto& row : n) {
    std::vector<double> r;
    try {
      r = row.as<std::vector<double>>();
    } catch (const YAML::Exception&) {
      fail(key, shape);
    }
    if (r.size() != cols) fail(key, shape);
    for (double x : r)
      if (!std::isfinite(x)) fail(key, "must hold finite numbers");
    v.insert(v.end(), r.begin(), r.end());
  }
  return v;
}

YamlMap YamlMap::map(const std::string& key) {
  const YAML::Node n = child(key);
  if (!n) fail(key, "is missing");
  return YamlMap(file_, n, path(key));
}

// A mapping key as a name. YAML allows any node as a key ("? [a, b]: 1"); none of ours is one,
// and yaml-cpp would throw its own exception converting it.
std::string YamlMap::key_name(const YAML::Node& key) const {
  if (!key.IsScalar())
    throw ConfigError(where(key) + ": '" + (path_.empty() ? "document" : path_) + "' has a key that is not a plain name");
  return key.Scalar();
}

std::vector<std::string> YamlMap::keys() const {
  std::vector<std::string> k;
  for (const auto& kv : node_) k.push_back(key_name(kv.first));
  return k;
}

void YamlMap::finish() const {
  for (const auto& kv : node_) {
    const std::string k = key_name(kv.first);
    if (!used_.count(k)) throw ConfigError(where(kv.first) + ": unknown key '" + path(k) + "'");
  }
}

}  // namespace rsd::formats
