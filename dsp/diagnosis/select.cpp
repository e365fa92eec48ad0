#include "dsp/diagnosis/select.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "dsp/diagnosis/clock_shape.hpp"
#include "dsp/diagnosis/forward_selection.hpp"
#include "dsp/diagnosis/selector.hpp"
#include "dsp/diagnosis/uncertainty.hpp"

namespace rsd::dsp {

namespace {

using selection::Selector;
using selection::State;

// The steps without effect e's (it left the selection).
void forget(std::vector<SelectedEffect>& steps, Effect e) {
  steps.erase(std::remove_if(steps.begin(), steps.end(), [&](const SelectedEffect& st) { return st.effect == e; }), steps.end());
}

// Undoes lens_model when, given the final set, the nominal family's lens does better: the two
// families are rival hypotheses for one structure, judged head to head as rivals are, the lower
// BIC winning. lens_model can win its round before the effects that share its structure come in
// (a walking phone's equidistant lens, four terms, took the barrel's and the focal length's part
// in ten seconds of shake, BIC drop 18 840; given the focal length the BIC was 32 lower with the
// nominal family, whose lens then put the focal length within 0.2%). Not the removal threshold:
// a pinhole camera behind a fisheye profile is told by parsimony alone (equidistant terms follow
// tan's series; the switch's two terms do as well as four, a BIC drop of 9). lens_distortion
// takes the step's place; why goes to `withheld`.
void back_to_the_nominal_family(const Selector& sel, State& s, std::vector<SelectedEffect>& steps,
                                std::vector<std::string>& withheld) {
  if (!s.has(Effect::LensModel)) return;
  State nominal = sel.nominal_family(s);
  const double drop = sel.drop(nominal, s);
  if (drop >= 0) return;
  std::ostringstream why;
  why << effect_name(Effect::LensModel) << " not named: given the others, the nominal family's lens does better (the BIC is "
      << std::lround(-drop) << " lower with it); named " << effect_name(Effect::LensDistortion) << " instead";
  withheld.push_back(why.str());
  if (sel.opt_.progress) sel.opt_.progress(withheld.back());
  s = std::move(nominal);
  for (SelectedEffect& st : steps)
    if (st.effect == Effect::LensModel) st.effect = Effect::LensDistortion;
}

// Drops any selected effect whose removal (with a refit of the rest) costs less BIC than
// the selection threshold: an earlier pick that later ones made redundant. Screened on the
// subsample, confirmed on the fitting set. What goes, and why, goes to `withheld` (the
// progress said it was named: the walking phone's principal point, named at a drop of 23 before
// the lens and the focal length came in, left the list without a word).
void backward(const Selector& sel, State& s, std::vector<SelectedEffect>& steps, std::vector<std::string>& withheld) {
  bool changed = true;
  while (changed && s.effects.size() > 1) {
    changed = false;
    const State here = sel.on_screen(s);
    for (Effect e : s.effects) {
      const double projected = sel.projected_drop(sel.remove(s, e, sel.screen_, sel.opt_.screen_iterations), here);
      if (projected >= sel.opt_.min_bic_drop + 30 + 0.05 * std::abs(projected)) continue;
      State c = sel.remove(s, e, sel.fit_, sel.opt_.max_iterations);
      const double drop = sel.drop(c, s);
      if (drop >= sel.opt_.min_bic_drop) continue;
      std::ostringstream why;
      why << effect_name(e) << " not named: named in an earlier round, it adds too little once the effects named after "
          << "it are in (";
      if (drop < 0) why << "the BIC is " << std::lround(-drop) << " lower without it)";
      else why << "BIC drop " << std::lround(drop) << ", under the threshold of " << std::lround(sel.opt_.min_bic_drop) << ")";
      withheld.push_back(why.str());
      if (sel.opt_.progress) sel.opt_.progress(withheld.back());
      s = std::move(c);
      forget(steps, e);
      changed = true;
      break;
    }
  }
}

// The selected effects judged latest first, again after each that goes, until all stay:
// `judge(e)` returns the state without e (the rest refitted) when e must go, else nothing.
// Says whether any went.
template <class Judge>
bool drop_latest_first(State& s, std::vector<SelectedEffect>& steps, Judge judge) {
  bool any = false;
  for (bool changed = true; changed && !s.effects.empty();) {
    changed = false;
    for (auto it = s.effects.rbegin(); it != s.effects.rend(); ++it) {
      const Effect e = *it;
      std::optional<State> without = judge(e);
      if (!without) continue;
      s = std::move(*without);  // invalidates `it`
      forget(steps, e);
      changed = any = true;
      break;
    }
  }
  return any;
}

// Drops any selected effect that does not hold out of its own half (says whether any did):
// with the others in, it must predict the blocked half it was not fitted on, both ways
// (Selector::consistent). A stand-in for physics outside the table (a clock that jumps, a gyro
// that clips) fits one half's structure and mispredicts the other's; the latest pick first.
bool consistency(const Selector& sel, State& s, std::vector<SelectedEffect>& steps) {
  return drop_latest_first(s, steps, [&](Effect e) -> std::optional<State> {
    const State without = sel.without_for_judging(s, e);
    double time_drop = 0, rate_drop = 0, apart = 0;
    const bool holds = sel.consistent(without, s, time_drop, rate_drop, apart);
    for (SelectedEffect& st : steps)
      if (st.effect == e) st.blocked_time_drop = time_drop, st.blocked_rate_drop = rate_drop;
    if (holds) return std::nullopt;
    if (sel.opt_.progress)
      sel.opt_.progress(std::string("dropped ") + effect_name(e) + ": it does not hold on the blocked halves" +
                        (apart > kHalvesAgreeSigmas ? " (they put its value " + std::to_string(std::lround(apart)) + " sigmas apart)" : ""));
    return sel.remove(s, e, sel.fit_, sel.opt_.max_iterations);
  });
}

// Drops clock_drift when the clock's offset, fitted window by window with the rest held, steps
// rather than grows along a line (clock_shape.hpp): a clock that jumps, which the table does not
// hold, and a drift only stands in for it. Before the blocked halves, so that they judge the rest
// without the stand-in (a time offset named beside it must then hold on its own). Says whether
// it went; why goes to `withheld`.
bool drift_is_a_rate(const Selector& sel, State& s, std::vector<SelectedEffect>& steps, std::vector<std::string>& withheld) {
  if (!s.has(Effect::ClockDrift)) return false;
  const ClockShape shape = clock_shape(sel.m_, s.params, sel.fit_, sel.sigma_);
  if (!shape.verdict.is_step) return false;
  const WeightedStep& step = shape.verdict.step;
  std::ostringstream why;
  why.precision(3);
  why << effect_name(Effect::ClockDrift) << " not named: the clock's offset, fitted over " << shape.windows.size()
      << " windows of time, steps by " << (step.after - step.before) * 1e3 << " ms near "
      << step.at - sel.m_.recording().nominal.time.t0 << " s rather than growing at a rate (chi-square "
      << std::lround(shape.verdict.line.chi2) << " about a line, " << std::lround(step.chi2)
      << " about a step): a clock that jumps, which no effect of the table describes";
  withheld.push_back(why.str());
  if (sel.opt_.progress) sel.opt_.progress(withheld.back());
  s = sel.remove(s, Effect::ClockDrift, sel.fit_, sel.opt_.max_iterations);
  forget(steps, Effect::ClockDrift);
  return true;
}

// Drops any selected effect whose value real hardware does not have, or that sits on its fit's
// bound (plausibility.hpp, unnameable_because), or that moves the predictions by less than an
// instrument's own bias (Selector::immaterial_because), refitting the rest; the latest pick is
// judged first. What was dropped, and why, goes to `withheld`.
void plausible_only(const Selector& sel, State& s, std::vector<SelectedEffect>& steps, std::vector<std::string>& withheld) {
  drop_latest_first(s, steps, [&](Effect e) -> std::optional<State> {
    std::string why = unnameable_because(s.params, e, sel.m_);
    if (why.empty()) why = sel.immaterial_because(s.params, e);
    if (why.empty()) return std::nullopt;
    withheld.push_back(std::string(effect_name(e)) + " not named: " + why);
    if (sel.opt_.progress) sel.opt_.progress(withheld.back());
    return sel.remove(s, e, sel.fit_, sel.opt_.max_iterations);
  });
}

// How far effect e's values in s lie from the nominal ones in their own uncertainty: the Wald
// statistic of its parameters (k of them) in their covariance at the fit, every named effect's
// parameters free at once (effect_uncertainties' covariances, the smallest statistic of them).
// nullopt when it cannot be judged: no continuous parameters, lens_model (a switch of family:
// its terms have no nominal values), or no covariance.
struct Deviation {
  double wald = 0;
  int k = 0;
};
std::optional<Deviation> deviation_from_nominal(const Selector& sel, const State& s, Effect e) {
  if (e == Effect::LensModel) return std::nullopt;
  const NominalModel& n = sel.m_.recording().nominal;
  std::vector<Param> free;
  for (Effect f : s.effects)
    for (Param q : params_in(effect_params(f, sel.lens_)))
      if (!follows(q, n) && std::find(free.begin(), free.end(), q) == free.end()) free.push_back(q);
  std::vector<int> rows;
  std::vector<double> delta;
  for (Param q : params_in(effect_params(e, sel.lens_)))
    if (const auto it = std::find(free.begin(), free.end(), q); it != free.end())
      rows.push_back(static_cast<int>(it - free.begin())), delta.push_back(s.params[q] - sel.nominal_[q]);
  if (rows.empty()) return std::nullopt;  // no parameter of its own (readout_direction): no Jacobian
  const std::vector<ParameterCovariance> covs = fitted_covariances(sel.m_, s.params, free, sel.fit_);
  if (covs.empty()) return std::nullopt;
  const Eigen::Map<const Eigen::VectorXd> d(delta.data(), static_cast<Eigen::Index>(delta.size()));
  Deviation out{std::numeric_limits<double>::infinity(), static_cast<int>(rows.size())};
  for (const ParameterCovariance& c : covs) out.wald = std::min(out.wald, c.wald(rows, d));
  return out;
}

// Why effect e of s must not be named for lying within its own uncertainty of the nominal values
// ("" when it lies beyond a 3-sigma deviation, wald_at_three_sigmas, or cannot be judged). The
// selection's BIC counts the observations as independent but for what a frame shares
// (design_effect); a flight's residuals are shared by the frames a stretch of its parallax
// spans, and the covariance clustered over blocks of frames sees it: the independent
// generator's drone named a focal length of 550.9 px for 540 (BIC drop 54) at 1.5 of its
// standard errors (7.4 px).
std::string within_its_uncertainty_because(const Selector& sel, const State& s, Effect e) {
  const std::optional<Deviation> dev = deviation_from_nominal(sel, s, e);
  if (!dev) return "";
  const double bar = wald_at_three_sigmas(dev->k);
  if (dev->wald >= bar) return "";
  std::ostringstream why;
  why.precision(3);
  why << "its value is within its own uncertainty of the nominal (" << std::sqrt(dev->wald)
      << " standard errors from it: chi-square " << dev->wald << " over " << dev->k << " parameter(s), where 3 sigmas are "
      << bar << ")";
  return why.str();
}

// Drops any selected effect whose value the data do not tell from the nominal
// (within_its_uncertainty_because), refitting the rest; the latest pick is judged first. What
// was dropped, and why, goes to `withheld`.
void told_from_the_nominal(const Selector& sel, State& s, std::vector<SelectedEffect>& steps,
                           std::vector<std::string>& withheld) {
  drop_latest_first(s, steps, [&](Effect e) -> std::optional<State> {
    const std::string why = within_its_uncertainty_because(sel, s, e);
    if (why.empty()) return std::nullopt;
    withheld.push_back(std::string(effect_name(e)) + " not named: " + why);
    if (sel.opt_.progress) sel.opt_.progress(withheld.back());
    return sel.remove(s, e, sel.fit_, sel.opt_.max_iterations);
  });
}

// Drops any selected effect that, given the others, does not improve the prediction of the
// held-out observations (issue 34, invariant c): the model without it (the others refitted on
// the fitting set) predicts them as well or better. Each round's winner had to lower the
// held-out chi-square when it came in; a later pick can take over what it did there, and the
// blocked halves, cut from the fitting observations, cannot see frames no fit saw. The latest
// pick is judged first; what was dropped, and why, goes to `withheld`.
void each_improves_held_out(const Selector& sel, State& s, std::vector<SelectedEffect>& steps,
                            std::vector<std::string>& withheld) {
  if (sel.held_.empty()) return;
  drop_latest_first(s, steps, [&](Effect e) -> std::optional<State> {
    const double drop = sel.heldout_drop(sel.without_for_judging(s, e), s);
    for (SelectedEffect& st : steps)
      if (st.effect == e) st.heldout_given_others = drop;
    if (drop > 0) return std::nullopt;
    std::ostringstream why;
    why << effect_name(e) << " not named: given the others it does not improve the held-out prediction (their robust "
        << "chi-square is " << std::lround(-drop) << " higher with it)";
    withheld.push_back(why.str());
    if (sel.opt_.progress) sel.opt_.progress(withheld.back());
    return sel.remove(s, e, sel.fit_, sel.opt_.max_iterations);
  });
}

}  // namespace

Selection select_effects(const DiagnosisModel& m, const std::vector<int>& fit, const std::vector<int>& held,
                         const std::vector<int>& screen, const ModelParams& nominal, const ModelParams& start,
                         double sigma_px, const SelectionOptions& opt) {
  const Selector sel(m, fit, held, screen, nominal, start, sigma_px, opt);
  State s = sel.initial();
  std::vector<std::string> withheld;
  std::vector<SelectedEffect> steps = selection::forward(sel, applicable_effects(m), s, withheld);
  back_to_the_nominal_family(sel, s, steps, withheld);
  backward(sel, s, steps, withheld);
  if (!opt.blocked_halves) return {steps, s.params, withheld, false, sel.stabilised_s_};
  if (opt.progress && !steps.empty()) opt.progress("checking the named effects on blocked halves (time, angular rate)");
  bool dropped = drift_is_a_rate(sel, s, steps, withheld);
  dropped = consistency(sel, s, steps) || dropped;
  plausible_only(sel, s, steps, withheld);
  told_from_the_nominal(sel, s, steps, withheld);
  each_improves_held_out(sel, s, steps, withheld);
  return {steps, s.params, withheld, dropped, sel.stabilised_s_};
}

Selection hold_on_blocked_halves(const DiagnosisModel& m, const std::vector<int>& fit, const std::vector<int>& held,
                                 const std::vector<int>& screen, const ModelParams& nominal, const ModelParams& start,
                                 double sigma_px, const SelectionOptions& opt, Selection chosen) {
  const Selector sel(m, fit, held, screen, nominal, start, sigma_px, opt);
  State s{{}, chosen.params, 0};
  for (const SelectedEffect& st : chosen.effects) s.effects.push_back(st.effect);  // one step per effect
  s.bic = sel.bic(s.params, s.effects, fit);
  if (opt.progress && !chosen.effects.empty()) opt.progress("checking the named effects on blocked halves (time, angular rate)");
  chosen.dropped_on_halves = drift_is_a_rate(sel, s, chosen.effects, chosen.withheld);
  chosen.dropped_on_halves = consistency(sel, s, chosen.effects) || chosen.dropped_on_halves;
  plausible_only(sel, s, chosen.effects, chosen.withheld);
  told_from_the_nominal(sel, s, chosen.effects, chosen.withheld);
  each_improves_held_out(sel, s, chosen.effects, chosen.withheld);
  chosen.params = s.params;
  return chosen;
}

}  // namespace rsd::dsp
