// rsd-diagnose's human-readable output: parameter uncertainties of the named effects, PLplot
// figures of the residual before (nominal model) and after (final fit), and REPORT_DIR/index.md,
// the page a person reads first. The JSON (the spec's "Diagnosis output") is written elsewhere
// and carries none of this, since the spec fixes its keys.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "dsp/diagnosis/diagnosis.hpp"

namespace rsd::tools {

// One fitted parameter of a named effect with its 1-sigma uncertainty (nullopt when it has
// none: the discrete readout direction, or a parameter the model does not expose).
struct ParamUncertainty {
  std::string effect, param;
  double value = 0;
  std::string text;  // non-numeric value (direction)
  std::optional<double> sigma;
};

// The held-out split diagnose() uses: every n-th frame in time order is held out.
bool held_out(const dsp::DiagnosisModel& m, int i, int heldout_every);

// Uncertainties of every named effect's parameters at the fit: numeric Jacobian (central
// differences) of the fitting-set inlier residuals with respect to all named effects'
// continuous parameters at once (so correlations between effects widen them); per parameter
// the larger of the classic s^2 (J^T J)^-1 (s the per-coordinate RMS of those residuals) and
// the sandwich estimate with residuals clustered by frame (errors a frame shares: gyro noise,
// stamp jitter). Derived parameters (frame_readout_s = line_delay_s x height) are propagated.
std::vector<ParamUncertainty> effect_uncertainties(const dsp::DiagnosisModel& m, const dsp::Diagnosis& d,
                                                   int heldout_every);

// The ModelParams index of a spec parameter name ("line_delay_s", "k1", "x", ...), if the
// diagnosis model has one by that name.
std::optional<dsp::Param> param_by_name(const std::string& name);

struct ReportInput {
  std::string recording_dir;
  const dsp::DiagnosisModel* model = nullptr;
  const dsp::Diagnosis* diagnosis = nullptr;
  int heldout_every = 5;
  double seconds = 0;  // how long the diagnosis took
};

// Writes REPORT_DIR/index.md and the PNG figures it embeds (creating the directory);
// returns the files written.
std::vector<std::string> write_report(const std::string& report_dir, const ReportInput& in);

}  // namespace rsd::tools
