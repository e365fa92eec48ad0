// Model-discrepancy diagnosis of an observation recording (docs/formats/recording-v1.md):
// how badly the nominal model fits (robust baseline), where the mismatch lives (located
// signals), and which named effects explain it (gross errors searched globally first, then
// robust fits and BIC forward selection with a backward check), with a held-out comparison
// on frames the fit did not see. Pure computation: the rsd-diagnose tool reads the files and
// writes the JSON and report. Method and measured accuracy: docs/diagnosis.md.
#pragma once

#include <array>
#include <functional>
#include <string>
#include <vector>

#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/locate.hpp"
#include "dsp/diagnosis/model.hpp"
#include "dsp/diagnosis/named_effect.hpp"
#include "dsp/diagnosis/parallax.hpp"
#include "dsp/diagnosis/remainder.hpp"
#include "dsp/diagnosis/robust_stats.hpp"
#include "dsp/diagnosis/uncertainty.hpp"

namespace rsd::dsp {

struct Diagnosis {
  RobustStats baseline;
  std::vector<Located> located;
  std::vector<NamedEffect> effects;  // in order of selection; empty = fits within noise
  ModelParams fitted;
  double sigma_px = 0;  // the residual sigma the fits and BIC used (noise_floor_px when known)
  // Scales a selection started from and ended far from (by over 25%), in order: each time the
  // selection ran again at the scale it ended with (sigma_px is the last).
  std::vector<double> sigma_restarts;
  double final_rms_px = 0;  // over the usable observations
  // The held-out comparison (issue 34's first invariant), the nominal model against the final one
  // on the held-out observations. Under parallax (the effects selected with the translation
  // nuisance) each held-out frame pair's translation is taken out of both, fitted to the held-out
  // pairs as a test image's pose is: the effects claim what a rotation leaves, and 1.7 px of a
  // drone's parallax against 0.5 px of noise swamped what its clock offset changes (the true
  // offset predicted the parallax and all worse than none). heldout_nominal is the nominal model
  // as compared (its translation_nuisance on under parallax, with the selection's spline);
  // heldout_model gives any model so. The same observations with the parallax in:
  // heldout_with_parallax_*_rms_px (without parallax, the comparison's own).
  double heldout_baseline_rms_px = 0, heldout_final_rms_px = 0;
  double heldout_with_parallax_baseline_rms_px = 0, heldout_with_parallax_final_rms_px = 0;
  ModelParams heldout_nominal;
  int heldout_observations = 0;
  // The held-out observations in the first and the second half of the recording's time (split at
  // the median frame time of the held-out observations): the nominal and the final model on each.
  // A model that predicts one half only is seen here even when the pooled RMS improves.
  struct HeldoutHalf {
    double baseline_rms_px = 0, final_rms_px = 0;
    int observations = 0;
  };
  std::array<HeldoutHalf, 2> heldout_halves{};
  int fit_observations = 30000;  // how many fitting observations the named values were fitted on (observation_choice.hpp)
  // The per-coordinate residual RMS that noise alone gives: noise_px for landmarks,
  // sqrt(2) noise_px for matches (the transfer carries frame_a's noise); 0 when the recording
  // states no noise.
  double noise_floor_px = 0;
  // Matches spanning a gyro gap longer than DiagnosisModel::max_gyro_gap (at the gross time
  // offset) cannot be predicted: they are left out of fit, final and held-out RMS.
  int unusable = 0;
  std::vector<int> heldout_indices;    // observations (DiagnosisModel order) left out of the fit
  std::vector<std::string> candidates;  // the effects considered for this recording's kinds
  ModelParams gross;                    // where the global search put offset and focal length
  std::vector<ParamUncertainty> uncertainties;  // of every named effect's parameters, in order
  // Matches: parallax in the residual of the richest rotation-only fit (when the recording
  // states no noise) or else of the first selection. When clear, the effects were selected with
  // each frame pair's translation taken out (parallax.hpp).
  Parallax parallax;
  Remainder remainder;  // what the named effects leave: noise, or structure the table lacks
  // Effects the fit found and the diagnosis did not name, each with why: a value real hardware
  // does not have or one on its bound, or a final model that predicted the held-out frames worse
  // than the nominal one (then nothing is named). Also said in remainder.summary.
  std::vector<std::string> withheld;
};

struct DiagnosisOptions {
  int heldout_every = kHeldoutEvery;  // every n-th frame is held out of the fit (0: none)
  double min_bic_drop = 10;       // "very strong" evidence on the usual BIC scale
  int max_iterations = 30;        // final fits
  int screen_observations = 5000;  // candidates are fitted on this many fitting observations
  // The fits see at most this many fitting observations (and a quarter as many held out),
  // chosen by the information they carry (observation_choice.hpp); under the translation
  // nuisance of matches with parallax the named effects' values come from a final fit on three
  // times as many (diagnosis.cpp); 0: all of them.
  int fit_observations = 30000;
  // Called on the caller's thread as the diagnosis moves on (a stage, an effect named), for
  // progress output on long runs; may be empty.
  std::function<void(const std::string&)> progress;
  // A step of a long stage done (SelectionOptions::step); may be empty.
  std::function<void(const std::string& stage, int done, int total)> step;
};

Diagnosis diagnose(const DiagnosisModel& m, const DiagnosisOptions& opt = {});
// The same on a recording's own model.
Diagnosis diagnose(const Recording& rec, const DiagnosisOptions& opt = {});

// `p` as the held-out comparison of `d` takes a model: with d.heldout_nominal's translation
// nuisance (none without parallax).
ModelParams heldout_model(const Diagnosis& d, ModelParams p);

}  // namespace rsd::dsp
