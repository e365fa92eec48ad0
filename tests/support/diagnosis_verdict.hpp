// What the end-to-end tests read back from the real tools: a command's exit status and output,
// and the diagnosis JSON (rsd-diagnosis/1, docs/formats/recording-v1.md): the named effects
// with their numeric parameters, the held-out RMS, the remainder's verdict and what was
// withheld. One reader for every test that runs rsd-diagnose as a user would.
#pragma once

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace rsd::test {

inline std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Runs a command with its output in `log`; returns the exit status.
inline int run(const std::string& cmd, const std::string& log) {
  const int rc = std::system((cmd + " > " + log + " 2>&1").c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

inline void must_run(const std::string& cmd, const std::string& log) {
  ASSERT_EQ(run(cmd, log), 0) << cmd << "\n" << slurp(log);
}

struct Verdict {
  std::vector<std::string> effects;
  std::map<std::string, std::map<std::string, double>> params;  // effect -> numeric parameters
  double line_delay_s = NAN;
  double heldout_baseline_rms_px = NAN, heldout_final_rms_px = NAN;
  // The held-out observations of the first and second half in time: nominal and final RMS.
  std::array<double, 2> half_baseline_rms_px{NAN, NAN}, half_final_rms_px{NAN, NAN};
  bool remainder_significant = false;
  std::vector<std::string> remainder_located;  // the remainder's signals, strongest first
  std::string withheld;                        // the JSON's withheld list, as written
};

namespace verdict_detail {
inline double number_after(const std::string& json, const std::string& key, size_t from = 0) {
  const size_t at = json.find("\"" + key + "\": ", from);
  return at == std::string::npos ? NAN : std::stod(json.substr(at + key.size() + 4));
}
}  // namespace verdict_detail

inline Verdict read_verdict(const std::string& json_file) {
  using verdict_detail::number_after;
  const std::string json = slurp(json_file);
  Verdict v;
  const size_t effects_at = json.find("\"effects\"");
  if (effects_at == std::string::npos) return v;
  const std::string effects = json.substr(effects_at, json.find("\"final\"") - effects_at);
  const std::regex effect("\\{\"name\": \"([a-z_]+)\", \"params\": \\{([^}]*)\\}"), param("\"([a-z_0-9]+)\": ([-+0-9.eE]+)");
  for (std::sregex_iterator it(effects.begin(), effects.end(), effect), end; it != end; ++it) {
    const std::string name = (*it)[1], list = (*it)[2];
    v.effects.push_back(name);
    for (std::sregex_iterator p(list.begin(), list.end(), param); p != end; ++p) v.params[name][(*p)[1]] = std::stod((*p)[2]);
  }
  if (v.params.count("rolling_shutter")) v.line_delay_s = v.params["rolling_shutter"]["line_delay_s"];
  const size_t held = json.find("\"heldout\"");
  v.heldout_baseline_rms_px = number_after(json, "baseline_rms_px", held);
  v.heldout_final_rms_px = number_after(json, "final_rms_px", held);
  size_t half = json.find("\"heldout_halves\"");
  for (int h = 0; h < 2 && half != std::string::npos; ++h) {
    half = json.find("{", half + 1);
    if (half == std::string::npos) break;
    v.half_baseline_rms_px[h] = number_after(json, "baseline_rms_px", half);
    v.half_final_rms_px[h] = number_after(json, "final_rms_px", half);
  }
  const size_t rem = json.find("\"remainder\"");
  v.remainder_significant = rem != std::string::npos && json.compare(rem, 33, "\"remainder\": {\"significant\": true") == 0;
  const std::string rest = rem == std::string::npos ? "" : json.substr(rem, json.find("\"withheld\"") - rem);
  const std::regex signal("\"signal\": \"([a-z_]+)\"");
  for (std::sregex_iterator it(rest.begin(), rest.end(), signal), end; it != end; ++it) v.remainder_located.push_back((*it)[1]);
  const size_t w = json.find("\"withheld\"");
  if (w != std::string::npos) v.withheld = json.substr(w, json.find(']', w) - w);
  return v;
}

}  // namespace rsd::test
