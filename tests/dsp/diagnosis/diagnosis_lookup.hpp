// Looking up what a diagnosis named, for the diagnosis tests: an effect by its spec name, one
// of its parameters, and the sorted list of names (for exact comparisons and messages).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "dsp/diagnosis/diagnosis.hpp"

namespace rsd::test {

inline const dsp::NamedEffect* find(const dsp::Diagnosis& d, const std::string& name) {
  const auto it = std::find_if(d.effects.begin(), d.effects.end(), [&](const dsp::NamedEffect& e) { return e.name == name; });
  return it == d.effects.end() ? nullptr : &*it;
}

// NaN (and a test failure when the effect is there but lacks the parameter) if absent.
inline double param(const dsp::NamedEffect* e, const std::string& name) {
  if (!e) return NAN;
  for (const auto& p : e->params)
    if (p.name == name) return p.value;
  ADD_FAILURE() << e->name << " has no parameter " << name;
  return NAN;
}

// The 1-sigma uncertainty the diagnosis reports for an effect's parameter; NaN if it has none.
inline double sigma(const dsp::Diagnosis& d, const std::string& effect, const std::string& name) {
  for (const auto& u : d.uncertainties)
    if (u.effect == effect && u.param == name && u.sigma) return *u.sigma;
  return NAN;
}

// The named effects, sorted, each followed by a space: "rolling_shutter time_offset ".
inline std::string names(const dsp::Diagnosis& d) {
  std::vector<std::string> n;
  for (const auto& e : d.effects) n.push_back(e.name);
  std::sort(n.begin(), n.end());
  std::string s;
  for (const auto& x : n) s += x + " ";
  return s;
}

// Every observation of a model, in order.
inline std::vector<int> every_observation(const dsp::DiagnosisModel& m) {
  std::vector<int> all(m.size());
  for (int i = 0; i < m.size(); ++i) all[i] = i;
  return all;
}

// Whether one of the diagnosis's withheld lines (what it found and did not name) says `what`.
inline bool said(const dsp::Diagnosis& d, const std::string& what) {
  for (const std::string& w : d.withheld)
    if (w.find(what) != std::string::npos) return true;
  return false;
}

// What a diagnosis named (sorted), its held-out RMS before and after, and what it withheld, on
// stdout: the test's log says what happened when an assertion fails.
inline void show(const dsp::Diagnosis& d) {
  std::printf("named [%s] held out %.3f -> %.3f px\n", names(d).c_str(), d.heldout_baseline_rms_px, d.heldout_final_rms_px);
  for (const std::string& w : d.withheld) std::printf("  withheld: %s\n", w.c_str());
}

}  // namespace rsd::test
