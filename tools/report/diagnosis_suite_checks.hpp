// The goals' checks of the benchmark suite, internal to it: what running a case
// (diagnosis_suite_run.cpp) takes from diagnosis_suite_checks.cpp.
#pragma once

#include <optional>

#include "tools/report/diagnosis_suite.hpp"
#include "dsp/diagnosis/diagnosis.hpp"
#include "dsp/sim/recording_simulation.hpp"

namespace rsd::tools {

// The true model as diagnosis parameters, if every true effect has a parameter in it.
std::optional<dsp::ModelParams> true_params(const dsp::SimulatedRecording& sim);

// The goals checked on the diagnosis `d` of the case `r` (whose checks name its effects and hold
// their shifts): each effect recovered, the named set, the held-out RMS against the noise floor
// the true model leaves, and the remainder.
void run_checks(CaseResult& r, const dsp::DiagnosisModel& m, const dsp::SimulatedRecording& sim, const dsp::Diagnosis& d);

}  // namespace rsd::tools
