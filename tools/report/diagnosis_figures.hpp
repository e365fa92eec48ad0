// The diagnosis report's figures (PLplot PNGs): the residual of the nominal and the final model
// against image row, radius and time and over the image, the field one named effect removes,
// and the final residual per frame (the remainder). diagnosis_report.cpp writes the pages that
// embed them.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "dsp/diagnosis/diagnosis.hpp"

namespace rsd::tools {

// One model's residuals over all observations, with the inlier flags of its own robust scale.
struct Residuals {
  std::vector<Eigen::Vector2d> r;
  std::vector<bool> in;
};
Residuals residuals_of(const dsp::DiagnosisModel& m, const dsp::ModelParams& p);

// What the figures show: the nominal (before) and final (after) residuals, the sigma, the
// residual axes, and each observation's row, radius and time since the first frame.
struct Figures {
  const dsp::DiagnosisModel& m;
  Residuals before, after;
  double sigma;
  double range_before = 0, range_after = 0;       // residual axes: +-range px
  std::vector<double> row, radius, time;          // per observation
};
Figures figures_of(const dsp::DiagnosisModel& m, const dsp::Diagnosis& d);

// The residual against `x` (one value per observation), before above after.
void residual_vs_figure(const Figures& f, const std::string& file, const std::vector<double>& x,
                        const std::string& what, const std::string& xlabel);
// The residual per image cell, before beside after.
void residual_map_figure(const Figures& f, const std::string& file);

// What one named effect removes: the residual of the model without it minus the final
// residual (inliers of the final model), and its per-coordinate RMS.
Residuals removed_by(const Figures& f, const dsp::ModelParams& no_effect);
double rms_of(const Residuals& r);
// That field per image cell, beside the final residual.
void effect_figure(const Figures& f, const Residuals& removed, const std::string& name, const std::string& file);
// The final residual's mean and RMS per frame over time, against the remainder's noise.
void remainder_figure(const Figures& f, const dsp::Remainder& rem, const std::string& file);

}  // namespace rsd::tools
