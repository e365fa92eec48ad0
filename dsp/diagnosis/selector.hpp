// The selector of dsp::select_effects (select.cpp): hypotheses about the effects fitted and
// judged on one recording's fitting, held-out and screening observations. Internal to the
// diagnosis; forward_selection.cpp runs its rounds, select.cpp checks the set they end with.
//
// Thread contract: a Selector's judgements do not change once built (it only remembers the
// states `remove` fitted and the states it fitted on the blocked halves); its methods may be
// called from one thread at a time (they evaluate the DiagnosisModel, which is not thread-safe,
// and fill that memory).
#pragma once

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "dsp/diagnosis/blocked_halves.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/heldout_check.hpp"
#include "dsp/diagnosis/instrument.hpp"
#include "dsp/diagnosis/offset_search.hpp"
#include "dsp/diagnosis/plausibility.hpp"
#include "dsp/diagnosis/robust_stats.hpp"
#include "dsp/diagnosis/select.hpp"
#include "dsp/diagnosis/stabiliser.hpp"
#include "dsp/geometry/lens_model.hpp"
#include "dsp/observation/observation_model.hpp"

namespace rsd::dsp::selection {

// Selector::worse_with_parallax_because's limit. In the suite a gyro scale and a lens standing in
// for a focal length under a hand-held shake came out 7.8 and 6.6 worse; the drone's shutter 0.9.
inline constexpr double kWorseSigmas = 3.0;

// The least an effect must move the predictions to be named (px, RMS per coordinate over the
// fitting set's inliers): the instrument's own bias (instrument.hpp).
inline constexpr double kMinShiftPx = kInstrumentBiasPx;

struct State {
  std::vector<Effect> effects;
  ModelParams params;
  double bic = 0;  // on the fitting set
  bool has(Effect e) const { return std::find(effects.begin(), effects.end(), e) != effects.end(); }
};

class Selector {
 public:
  Selector(const DiagnosisModel& m, const std::vector<int>& fit, const std::vector<int>& held,
           const std::vector<int>& screen, const ModelParams& nominal, const ModelParams& start, double sigma,
           const SelectionOptions& opt)
      : m_(m), fit_(fit), held_(held), screen_(screen), nominal_(nominal), start_(start), sigma_(sigma), opt_(opt),
        time_halves_(time_halves(m, screen)), rate_halves_(m.has_gyro() ? rate_halves(m, screen, start) : Halves{}),
        stabilised_s_(opt.stabilised_s), lens_(m.recording().nominal.cam.dist.model),
        field_(widest_ray_angle(m.recording().nominal.cam)) {}

  // Whether adding an effect (poorer -> richer) holds on the blocked halves (blocked_halves.hpp)
  // in time and, in gyro recordings, on the frames of low and of high angular rate (every effect
  // there shows through the rate: a stand-in for a gyro that clips fits only the fast frames):
  // it predicts the half it was not fitted on, and the two halves agree on its value within
  // kHalvesAgreeSigmas. The drops (the worse direction of each split; NaN where a split does
  // not apply) go to `time_drop` and `rate_drop`, the larger disagreement to `apart`.
  bool consistent(const State& poorer, const State& richer, double& time_drop, double& rate_drop, double& apart) const {
    time_drop = rate_drop = std::numeric_limits<double>::quiet_NaN(), apart = 0;
    const Hypothesis p{poorer.params, mask_of(poorer.effects, lens_)}, r{richer.params, mask_of(richer.effects, lens_)};
    for (auto [h, drop] : {std::pair{&time_halves_, &time_drop}, std::pair{&rate_halves_, &rate_drop}}) {
      if (!h->usable()) continue;
      const HalvesVerdict v = cross_check(m_, *h, fit_halves(m_, *h, p, sigma_, opt_.screen_iterations), p.free,
                                          on_halves(*h, richer, r), r.free, sigma_);
      *drop = v.drop, apart = std::max(apart, v.apart_sigmas);
    }
    // A drop of exactly zero is a half that cannot show the effect (no motion there): it holds.
    return !(time_drop < 0) && !(rate_drop < 0) && apart <= kHalvesAgreeSigmas;
  }

  // BIC = robust chi-square + k ln(2N) + the implausibility of the values (plausibility.hpp):
  // each switch (the readout's flip, the other lens family) counts as one parameter.
  double bic(const ModelParams& p, const std::vector<Effect>& effects, const std::vector<int>& idx) const {
    return robust_chi2(m_.residuals(p, idx), sigma_) + k_of({effects, p, 0}) * std::log(2.0 * idx.size()) +
           implausibility(p, effects);
  }

  State initial() const { return {{}, nominal_, bic(nominal_, {}, fit_)}; }

  // s with its BIC on the screening subsample (what screened hypotheses are compared with).
  State on_screen(const State& s) const { return {s.effects, s.params, bic(s.params, s.effects, screen_)}; }

  // The hypothesis "s plus e", fitted on the screening subsample. Remembered: a round that named
  // nothing is followed by one that asks every candidate again, the same ones from the same
  // state (under a hand-held shake's parallax a tenth of the diagnosis).
  State screen_add(const State& s, Effect e) const {
    return remembered(FitKind::Add, s, e, &screen_, opt_.screen_iterations, [&](FitEnd& end) { return fit_add(s, e, end); });
  }

  // s without e, fitted on idx from s's values. Remembered: the blocked halves and the held-out
  // check ask for the same states of the same selection (each a refit on every fitting
  // observation, a third of a diagnosis under the translation nuisance).
  State remove(const State& s, Effect e, const std::vector<int>& idx, int iterations) const {
    return remembered(FitKind::Remove, s, e, &idx, iterations,
                      [&](FitEnd& end) { return fit_remove(s, e, idx, iterations, end); });
  }

  // s without e, for the checks that judge e given the others (the blocked halves, the held-out
  // frames): they ask whether s does better than the rest refitted without e. Where e's removal
  // costs the fitting set far more than any of those checks could turn on after kJudgeIterations
  // (a 400 ms clock offset taken out: the rest crawl for 30 iterations to a chi-square still
  // twice s's, a tenth of a walking phone's diagnosis under parallax), the refit stops there;
  // else it runs to the end, as the state that replaces s when e goes must (remove).
  State without_for_judging(const State& s, Effect e) const {
    const State quick = remove(s, e, fit_, std::min(kJudgeIterations, opt_.max_iterations));
    if (quick.bic - s.bic > kDecisiveBicRise) return quick;
    return remove(s, e, fit_, opt_.max_iterations);
  }
  static constexpr int kJudgeIterations = 10;
  static constexpr double kDecisiveBicRise = 1e4;

  // lens_model: the other family's lens, starting from its nearest stand-in for the lens the
  // state has (over the image's field); it takes lens_distortion's place, whose terms it frees.
  void switch_lens(std::vector<Effect>& effects, ModelParams& p) const {
    lens_family_to(true, p);
    effects.erase(std::remove(effects.begin(), effects.end(), Effect::LensDistortion), effects.end());
  }

  // s with lens_model undone: the nominal family's lens in its place, starting from its nearest
  // stand-in for the lens s has, as lens_distortion; refitted on every fitting observation.
  State nominal_family(const State& s) const {
    std::vector<Effect> effects;
    for (Effect f : s.effects) effects.push_back(f == Effect::LensModel ? Effect::LensDistortion : f);
    ModelParams p = s.params;
    lens_family_to(false, p);
    p = fit_params(m_, fit_, p, mask_of(effects, lens_), sigma_, opt_.max_iterations);
    return {effects, p, bic(p, effects, fit_)};
  }

  // A screened hypothesis refitted on every fitting observation. Remembered, as screen_add.
  State refit_all(const State& screened) const {
    return remembered(FitKind::Refit, screened, Effect{}, &fit_, opt_.max_iterations, [&](FitEnd& end) {
      const ModelParams p =
          fit_params(m_, fit_, screened.params, mask_of(screened.effects, lens_), sigma_, opt_.max_iterations, &end);
      return State{screened.effects, p, bic(p, screened.effects, fit_)};
    });
  }

  // BIC drop from `poorer` to `richer` (both on the fitting set), with the chi-square drop
  // shrunk by the richer model's design effect (design_effect).
  double drop(const State& poorer, const State& richer) const {
    const double D = design_effect(m_, richer.params, fit_, sigma_);
    const double pen = std::log(2.0 * fit_.size()), dk = k_of(richer) - k_of(poorer);
    const double prior0 = implausibility(poorer.params, poorer.effects), prior1 = implausibility(richer.params, richer.effects);
    return ((poorer.bic - k_of(poorer) * pen - prior0) - (richer.bic - k_of(richer) * pen - prior1)) / D - dk * pen -
           (prior1 - prior0);
  }
  // The screening subsample's BIC drop projected onto the fitting set: the chi-square drop grows
  // with the number of observations, the penalty with its logarithm.
  double projected_drop(const State& from, const State& to) const {
    const double rho = static_cast<double>(screen_.size()) / static_cast<double>(fit_.size());
    const double k_from = k_of(from), k_to = k_of(to);
    const double prior_from = implausibility(from.params, from.effects), prior_to = implausibility(to.params, to.effects);
    const double chi2_drop = (from.bic - k_from * std::log(2.0 * screen_.size()) - prior_from) -
                             (to.bic - k_to * std::log(2.0 * screen_.size()) - prior_to);
    return chi2_drop / rho - (k_to - k_from) * std::log(2.0 * fit_.size()) - (prior_to - prior_from);
  }
  double k_of(const State& s) const {
    return static_cast<double>(mask_of(s.effects, lens_).count()) + (s.params.flip_readout ? 1 : 0) + (s.params.other_lens ? 1 : 0);
  }

  double rms(const ModelParams& p) const { return robust_stats(m_.residuals(p, fit_)).rms_px; }

  // Whether `richer` explains the bulk of what `poorer` leaves, not only its tail: its robust
  // chi-square on `poorer`'s inliers (the fitting observations within kOutlierSigmas robust
  // scales) must not rise. A real effect's structure runs through the bulk. A hypothesis that
  // bends the model towards the outliers (a near bus's parallax seen from a car, cars moving
  // under a drone) lowers the whole chi-square, and the held-out one, since the same outliers
  // are there too, while every other residual grows: the phone on a dashboard wanted a gyro
  // bias of 0.63 rad/s that raised the robust scale from 0.69 to 1.20 px. "" when it does;
  // else why not.
  std::string fits_the_tail_because(const State& poorer, const State& richer) const {
    const std::vector<Eigen::Vector2d> r = m_.residuals(poorer.params, fit_);
    const std::vector<bool> in = inliers(r);
    std::vector<int> bulk;
    for (size_t k = 0; k < fit_.size(); ++k)
      if (in[k]) bulk.push_back(fit_[k]);
    // Both models on the bulk alone, `poorer` again too: under the translation nuisance the
    // residuals depend on the set they are taken over (its velocity is fitted to that set).
    const double before = robust_chi2(m_.residuals(poorer.params, bulk), sigma_);
    const double after = robust_chi2(m_.residuals(richer.params, bulk), sigma_);
    if (after <= before) return "";
    std::ostringstream why;
    why << "it fits the outliers (" << (fit_.size() - bulk.size()) << " of " << fit_.size()
        << " fitting observations beyond " << kOutlierSigmas << " robust scales) at the cost of the rest: its chi-square on the "
        << bulk.size() << " others rises by " << std::lround(after - before)
        << " (structure outside the table in the tail, such as a near object's parallax or moving things)";
    return why.str();
  }

  // Why e, at its values in p beside the others', is too small to name ("" when it is not):
  // with its values set back (the rest as they are) the predictions of the fitting set's
  // inliers move by less than kMinShiftPx.
  std::string immaterial_because(const ModelParams& p, Effect e) const {
    const std::vector<Eigen::Vector2d> with = m_.residuals(p, fit_), without = m_.residuals(without_values(p, e), fit_);
    const std::vector<bool> in = inliers(with);
    double sum = 0;
    size_t n = 0;
    for (size_t k = 0; k < with.size(); ++k)
      if (in[k] && without[k].allFinite()) sum += (with[k] - without[k]).squaredNorm(), ++n;
    const double shift = n ? std::sqrt(0.5 * sum / static_cast<double>(n)) : 0.0;
    if (shift >= kMinShiftPx) return "";
    std::ostringstream why;
    why.precision(2);
    why << "it moves the predictions by " << shift << " px (RMS per coordinate), under the " << kMinShiftPx
        << " px a target detector's or a tracker's own bias reaches: too small to tell from the instrument";
    return why.str();
  }

  // Robust chi-square drop on the held-out observations from `poorer` to `richer` (0 when
  // nothing is held out).
  double heldout_drop(const State& poorer, const State& richer) const {
    if (held_.empty()) return 0;
    return robust_chi2(m_.residuals(poorer.params, held_), sigma_) - robust_chi2(m_.residuals(richer.params, held_), sigma_);
  }

  // Under the translation nuisance, whether `richer` predicts the held-out observations worse
  // than `poorer` with the nuisance off, as the final model is judged too (heldout_check.hpp,
  // the first invariant; worse_with_parallax). "" when not, or when there is no nuisance.
  std::string worse_with_parallax_because(const State& poorer, const State& richer) const {
    if (held_.empty() || !richer.params.translation_nuisance) return "";
    const std::string worse = worse_with_parallax(m_, held_, poorer.params, richer.params);
    if (worse.empty()) return "";
    return "with the camera's translation left in, it predicts the held-out frames worse than without it " + worse;
  }

  // Whether `richer` stands in for a video stabilised in the camera (stabiliser.hpp): an effect
  // of `added` gives the gyro's motion a gain under one (a gyro scale under one on every axis; a
  // focal length shorter than `poorer`'s), or one did before in this selection, and `poorer`
  // seen through the gyro smoothed fits the fitting set better than `richer` by over
  // min_bic_drop (the chi-square drop over the design effect, as drop's). Once a gain has been
  // found to stand in for the stabiliser, whatever else is asked must beat it too: a lens and a
  // principal point came next on a stabilised clip, stand-ins as well. A tie keeps the effect
  // (the smoothing's one parameter against the effect's is no evidence either way). "" when not.
  std::string stands_in_for_a_stabiliser_because(const State& poorer, const State& richer,
                                                 const std::vector<Effect>& added) const {
    if (!m_.has_gyro()) return "";
    const ModelParams& r = richer.params;
    const auto shrinks = [&](Effect e) {
      if (e == Effect::GyroScale) return std::max({r[Param::ScaleX], r[Param::ScaleY], r[Param::ScaleZ]}) < 1;
      return e == Effect::FocalLength && r[Param::Fx] < poorer.params[Param::Fx];
    };
    if (!stabilised_s_ && std::none_of(added.begin(), added.end(), shrinks)) return "";
    const StabiliserFit& s = stabiliser_at(poorer);
    const double with = robust_chi2(m_.residuals(r, fit_), sigma_);
    const double D = design_effect(m_, r, fit_, sigma_);
    if (!((with - s.chi2) / D > opt_.min_bic_drop)) return "";
    stabilised_s_ = s.sigma_s;
    std::ostringstream why;
    why << "it stands in for a video stabilised in the camera: the pictures follow the gyro smoothed over "
        << std::lround(1e3 * s.sigma_s) << " ms (a Gaussian's sigma) better than with it (chi-square " << std::lround(with)
        << " -> " << std::lround(s.chi2) << " on the fitting set)";
    return why.str();
  }

  const DiagnosisModel& m_;
  const std::vector<int>& fit_;
  const std::vector<int>& held_;
  const std::vector<int>& screen_;
  ModelParams nominal_, start_;
  double sigma_;
  const SelectionOptions& opt_;
  Halves time_halves_, rate_halves_;
  // The smoothing's sigma once a gain has stood in for a stabiliser in this selection, or as
  // found after a selection before it (SelectionOptions::stabilised_s).
  mutable std::optional<double> stabilised_s_;
  LensModel lens_;  // the nominal lens's family
  double field_;    // the largest angle off the axis the image sees (radians), through the nominal lens

 private:
  // p's lens as the other family's (other) or the nominal family's: the family's nearest stand-in
  // for the lens p has over the image's field, its start.
  void lens_family_to(bool other, ModelParams& p) const {
    const NominalModel& n = m_.recording().nominal;
    const Distortion now = lens_of(n, p);
    p.other_lens = other;
    set_lens_terms(p, nearest_lens(now, lens_family(n, p), field_));
  }
  // screen_add's and remove's fits.
  State fit_add(const State& s, Effect e, FitEnd& end) const {
    std::vector<Effect> effects = s.effects;
    effects.push_back(e);
    ModelParams p = s.params;
    for (int k = 0; k < kParamCount; ++k)
      if (effect_params(e, lens_)[k]) p.v[k] = start_.v[k];
    if (e == Effect::LensModel) switch_lens(effects, p);
    if (e == Effect::ReadoutDirection) {
      p.flip_readout = true;
      // The order of rows read means nothing without a readout time: a nominal global
      // shutter brings rolling_shutter along.
      if (!s.has(Effect::RollingShutter) && nominal_[Param::LineDelay] == 0) effects.push_back(Effect::RollingShutter);
    }
    if (e == Effect::TimeOffset) p[Param::TimeOffset] = refine_time_offset(m_, screen_, p, sigma_);
    p = fit_params(m_, screen_, p, mask_of(effects, lens_), sigma_, opt_.screen_iterations, &end);
    return {effects, p, bic(p, effects, screen_)};
  }
  State fit_remove(const State& s, Effect e, const std::vector<int>& idx, int iterations, FitEnd& end) const {
    std::vector<Effect> effects;
    for (Effect f : s.effects)
      if (f != e) effects.push_back(f);
    const ModelParams p = fit_params(m_, idx, without_values(s.params, e), mask_of(effects, lens_), sigma_, iterations, &end);
    return {effects, p, bic(p, effects, idx)};
  }
  // p with e's values back at the nominal ones and its switch off, the rest as they are.
  ModelParams without_values(ModelParams p, Effect e) const {
    const ParamMask drop = effect_params(e, lens_);
    for (int k = 0; k < kParamCount; ++k)
      // With its followers (fy follows fx): a focal length withdrawn left fy 26% off on a real clip.
      if (drop[k]) set_param(p, static_cast<Param>(k), nominal_.v[k], m_.recording().nominal);
    if (e == Effect::ReadoutDirection) p.flip_readout = false;
    if (e == Effect::LensModel) p.other_lens = false;
    return p;
  }
  static bool same(const ModelParams& a, const ModelParams& b) {
    return a.v == b.v && a.flip_readout == b.flip_readout && a.other_lens == b.other_lens &&
           a.translation_nuisance == b.translation_nuisance && a.translation_knot_s == b.translation_knot_s &&
           a.translation_depth_px == b.translation_depth_px && a.translation_world_plane == b.translation_world_plane;
  }
  // `richer` (hypothesis r) fitted on both halves of h, with the fits' covariances. Remembered:
  // the blocked halves judge each named effect against the same richer state.
  const CovariedHalves& on_halves(const Halves& h, const State& richer, const Hypothesis& r) const {
    for (const FittedHalves& f : halves_fits_)
      if (f.h == &h && f.of.effects == richer.effects && same(f.of.params, richer.params)) return f.fits;
    halves_fits_.push_back({&h, richer, with_covariances(m_, h, r.free, fit_halves(m_, h, r, sigma_, opt_.screen_iterations))});
    return halves_fits_.back().fits;
  }
  struct FittedHalves {
    const Halves* h;
    State of;
    CovariedHalves fits;
  };
  mutable std::deque<FittedHalves> halves_fits_;  // a deque: on_halves hands out references
  // `poorer` seen through the gyro smoothed (fit_stabiliser: the smoothing searched on the
  // screening subsample, poorer's effects refitted on the fitting set). Remembered: a round asks
  // it of each of its gains and their pair at the same state.
  const StabiliserFit& stabiliser_at(const State& poorer) const {
    for (const auto& [of, fit] : stabilisers_)
      if (of.effects == poorer.effects && same(of.params, poorer.params)) return fit;
    stabilisers_.emplace_back(poorer, fit_stabiliser(m_, screen_, fit_, poorer.params, mask_of(poorer.effects, lens_),
                                                     sigma_, opt_.max_iterations));
    return stabilisers_.back().second;
  }
  mutable std::deque<std::pair<State, StabiliserFit>> stabilisers_;
  // The fits a selection asks for more than once, by what they started from.
  enum class FitKind { Add, Refit, Remove };
  struct Remembered {
    FitKind kind;
    State from;
    Effect e;
    const std::vector<int>* idx;
    int iterations;
    FitEnd end;
    State to;
  };
  mutable std::vector<Remembered> remembered_;
  // A fit from the same start that converged in fewer iterations than asked is the same fit (FitEnd): the
  // judging removal's quick refit (without_for_judging) converges in 2-4 iterations mostly, and
  // the whole one after it was the same fit again (three of the walking phone's five effects:
  // a refit on every fitting observation each).
  template <class Fit>
  State remembered(FitKind kind, const State& from, Effect e, const std::vector<int>* idx, int iterations, const Fit& fit) const {
    for (const Remembered& r : remembered_) {
      const bool as_asked = r.iterations == iterations || (r.end.converged && r.end.iterations < iterations);
      if (r.kind == kind && r.e == e && r.idx == idx && as_asked && r.from.effects == from.effects &&
          same(r.from.params, from.params))
        return r.to;
    }
    FitEnd end;
    State to = fit(end);
    remembered_.push_back({kind, from, e, idx, iterations, end, to});
    return to;
  }
};

}  // namespace rsd::dsp::selection
