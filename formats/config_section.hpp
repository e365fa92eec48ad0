// One description of a configuration section serves both reading it and printing its
// defaults. A section is a function that visits each key once, with the struct field that
// holds its value: before reading, that is the default. So every default is written once, in
// the struct, and `rsd --print-default-config` cannot disagree with what rsd assumes.
//
// Two visitors: ConfigReader (strict reading through YamlMap: unknown keys and bad values are
// errors naming file, line and key) and DefaultsPrinter (YAML text with comments).
#pragma once

#include <Eigen/Core>

#include <functional>
#include <initializer_list>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "dsp/core/pixel_format.hpp"
#include "formats/yaml_map.hpp"

namespace rsd::formats {

class ConfigSection {
 public:
  virtual ~ConfigSection() = default;
  virtual void value(const char* key, double& v, const char* comment = nullptr) = 0;
  virtual void value(const char* key, int& v, const char* comment = nullptr) = 0;
  virtual void value(const char* key, unsigned& v, const char* comment = nullptr) = 0;
  virtual void value(const char* key, bool& v, const char* comment = nullptr) = 0;
  virtual void value(const char* key, std::string& v, const char* comment = nullptr) = 0;
  virtual void value(const char* key, Eigen::Vector3d& v, const char* comment = nullptr) = 0;
  // Nine numbers, row-major.
  virtual void value(const char* key, Eigen::Matrix3d& v, const char* comment = nullptr) = 0;
  // A key naming one of an enum's values.
  template <class E>
  void choice(const char* key, E& v, std::initializer_list<std::pair<const char*, E>> names, const char* comment = nullptr) {
    std::vector<std::string> texts;
    std::string text;
    for (const auto& [name, e] : names) {
      texts.emplace_back(name);
      if (e == v) text = name;
    }
    if (!choice_text(key, text, texts, comment)) return;
    for (const auto& [name, e] : names)
      if (text == name) v = e;
  }
  // A key naming a pixel format (dsp/core/pixel_format.hpp: "mono8", "nv12", "bayer_rggb16", ...).
  void pixel_format(const char* key, dsp::PixelFormat& v, const char* comment = nullptr);
  // A key naming a file: a relative path is taken from the configuration file's directory.
  void path(const char* key, std::string& v, const char* comment = nullptr);
  // A nested section; absent when reading leaves the values as they are.
  virtual void section(const char* key, const std::function<void(ConfigSection&)>& body, const char* comment = nullptr) = 0;
  // A comment line in the printed defaults (examples of optional keys, explanations).
  virtual void note(const std::string& text) = 0;
  // Validation: fails naming the key when reading; printing checks nothing.
  virtual void check(bool ok, const char* key, const std::string& why) = 0;
  // Reading: whether the file gives the key. Printing: false.
  virtual bool has(const char* key) const = 0;
  // The file being read ("" when printing): relative paths in it are taken from its directory.
  virtual std::string file() const = 0;

 protected:
  // Reading: sets `text` from the file (checked against `names`); false when absent.
  virtual bool choice_text(const char* key, std::string& text, const std::vector<std::string>& names, const char* comment) = 0;
};

class ConfigReader final : public ConfigSection {
 public:
  explicit ConfigReader(YamlMap m) : m_(std::move(m)) {}
  void value(const char* key, double& v, const char* comment = nullptr) override;
  void value(const char* key, int& v, const char* comment = nullptr) override;
  void value(const char* key, unsigned& v, const char* comment = nullptr) override;
  void value(const char* key, bool& v, const char* comment = nullptr) override;
  void value(const char* key, std::string& v, const char* comment = nullptr) override;
  void value(const char* key, Eigen::Vector3d& v, const char* comment = nullptr) override;
  void value(const char* key, Eigen::Matrix3d& v, const char* comment = nullptr) override;
  void section(const char* key, const std::function<void(ConfigSection&)>& body, const char* comment = nullptr) override;
  void note(const std::string&) override {}
  void check(bool ok, const char* key, const std::string& why) override;
  bool has(const char* key) const override { return m_.has(key); }
  std::string file() const override { return m_.file(); }
  YamlMap& map() { return m_; }
  // Rejects keys no visit read.
  void finish() const { m_.finish(); }

 protected:
  bool choice_text(const char* key, std::string& text, const std::vector<std::string>& names, const char* comment) override;

 private:
  YamlMap m_;
};

class DefaultsPrinter final : public ConfigSection {
 public:
  explicit DefaultsPrinter(int indent = 0) : indent_(indent) {}
  void value(const char* key, double& v, const char* comment = nullptr) override;
  void value(const char* key, int& v, const char* comment = nullptr) override;
  void value(const char* key, unsigned& v, const char* comment = nullptr) override;
  void value(const char* key, bool& v, const char* comment = nullptr) override;
  void value(const char* key, std::string& v, const char* comment = nullptr) override;
  void value(const char* key, Eigen::Vector3d& v, const char* comment = nullptr) override;
  void value(const char* key, Eigen::Matrix3d& v, const char* comment = nullptr) override;
  void section(const char* key, const std::function<void(ConfigSection&)>& body, const char* comment = nullptr) override;
  void note(const std::string& text) override;
  void check(bool, const char*, const std::string&) override {}
  bool has(const char*) const override { return false; }
  std::string file() const override { return {}; }
  std::string text() const { return out_.str(); }

 protected:
  bool choice_text(const char* key, std::string& text, const std::vector<std::string>& names, const char* comment) override;

 private:
  void line(const char* key, const std::string& value, const char* comment);
  int indent_;
  std::ostringstream out_;
};


}  // namespace rsd::formats
