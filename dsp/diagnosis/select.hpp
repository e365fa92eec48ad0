// Which named effects (docs/formats/recording-v1.md, "Named effects") explain a
// recording: BIC forward selection with a backward check. Candidates are screened on a
// subsample of the fitting observations; only the winner of a round is refitted on them all.
#pragma once

#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "dsp/diagnosis/effects.hpp"
#include "dsp/diagnosis/model.hpp"

namespace rsd::dsp {


struct SelectionOptions {
  double min_bic_drop = 10;
  int max_iterations = 30;         // final fits
  int screen_iterations = 8;       // candidate fits on the subsample
  std::function<void(const std::string&)> progress;  // an effect named or dropped (may be empty)
  // A step of a long stage done: `done` of `total` (the candidates a forward round screens), so
  // that a caller can draw a bar and say the time left of the stage (may be empty).
  std::function<void(const std::string& stage, int done, int total)> step;
  // Whether select_effects ends with the blocked-halves check (hold_on_blocked_halves).
  bool blocked_halves = true;
  // A stabiliser already found (seconds, the smoothing's sigma), by the check after a selection
  // that never asked (stabiliser_after_selection): every candidate must beat the smoothing from
  // the first round, as once the Selector has found a gain standing in for one.
  std::optional<double> stabilised_s;
};

struct SelectedEffect {
  Effect effect;
  double rms_px;    // fitting-set RMS once it (and those before it) is in
  double bic_drop;  // how much BIC fell when it was added
  double heldout_drop;  // how much the held-out robust chi-square fell (0: nothing held out)
  // Hypotheses for the same structure that came within min_bic_drop of it, head to head on all
  // fitting observations: the data cannot tell them from it.
  std::vector<Effect> rivals;
  // The robust chi-square drop on the unseen blocked half plus the margin its noise allows
  // (3 sqrt of the effect's signal energy there; the worse direction), in time and in angular
  // rate (gyro recordings); positive: it holds. NaN where not applicable.
  double blocked_time_drop = std::numeric_limits<double>::quiet_NaN();
  double blocked_rate_drop = std::numeric_limits<double>::quiet_NaN();
  // The held-out robust chi-square drop from the final model without it to the final model (the
  // others refitted): what it adds given the others. NaN where nothing is held out.
  double heldout_given_others = std::numeric_limits<double>::quiet_NaN();
};

struct Selection {
  std::vector<SelectedEffect> effects;  // in order of selection
  ModelParams params;                   // fitted; nominal values for the effects not selected
  // Effects the selection chose and did not name, each with why (unnameable_because).
  std::vector<std::string> withheld;
  // Whether the blocked halves, or the clock's shape (a drift that is a step: clock_shape.hpp),
  // dropped an effect the rounds had chosen (a stand-in).
  bool dropped_on_halves = false;
  // When a gain stood in for a video stabilised in the camera (stabiliser.hpp): the sigma of
  // the smoothing the pictures follow better (seconds).
  std::optional<double> stabiliser_sigma_s;
};

// `start` holds the gross estimates (gross_start) the candidates start from; `nominal` the
// values of the effects not selected. An effect is added only when it lowers BIC on `fit` by
// more than min_bic_drop AND lowers the robust chi-square of the `held` observations, which
// no fit saw (an over-fitted parameter explains noise of the fitting set only).
Selection select_effects(const DiagnosisModel& m, const std::vector<int>& fit, const std::vector<int>& held,
                         const std::vector<int>& screen,
                         const ModelParams& nominal, const ModelParams& start, double sigma_px,
                         const SelectionOptions& opt);

// The blocked-halves check of a selection made without it (SelectionOptions::blocked_halves
// false): a clock drift must be a rate (the clock's offset window by window on a line, not a
// step: clock_shape.hpp); every named effect must predict the half of the recording it was not
// fitted on, both ways, in time and (gyro recordings) in angular rate; those that do not are
// dropped and the rest refitted. Then the plausibility check, and each effect must, given the others,
// improve the prediction of the held-out observations on its own (what does not is withheld,
// with why). The same arguments as the selection had.
Selection hold_on_blocked_halves(const DiagnosisModel& m, const std::vector<int>& fit, const std::vector<int>& held,
                                 const std::vector<int>& screen, const ModelParams& nominal, const ModelParams& start,
                                 double sigma_px, const SelectionOptions& opt, Selection chosen);

}  // namespace rsd::dsp
