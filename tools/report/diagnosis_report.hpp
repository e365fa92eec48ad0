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

struct ReportInput {
  std::string recording_dir;
  const dsp::DiagnosisModel* model = nullptr;
  const dsp::Diagnosis* diagnosis = nullptr;
  int heldout_every = dsp::kHeldoutEvery;
  double seconds = 0;  // how long the diagnosis took
};

// Writes REPORT_DIR/index.md and the PNG figures it embeds (creating the directory);
// returns the files written.
std::vector<std::string> write_report(const std::string& report_dir, const ReportInput& in);

}  // namespace rsd::tools
