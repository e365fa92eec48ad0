#include "dsp/diagnosis/select.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "dsp/diagnosis/blocked_halves.hpp"
#include "dsp/diagnosis/robust_stats.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/plausibility.hpp"
#include "dsp/geometry/lens_model.hpp"
#include "dsp/observation/observation_model.hpp"

namespace rsd::dsp {

namespace {

// Selector::worse_with_parallax_because's limit. In the suite a gyro scale and a lens standing in
// for a focal length under a hand-held shake came out 7.8 and 6.6 worse; the drone's shutter 0.9.
constexpr double kWorseSigmas = 3.0;

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
        lens_(m.recording().nominal.cam.dist.model), field_(widest_ray_angle(m.recording().nominal.cam)) {}

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
      const HalvesVerdict v = cross_check(m_, *h, p, r, sigma_, opt_.screen_iterations);
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

  // The hypothesis "s plus e", fitted on the screening subsample.
  State screen_add(const State& s, Effect e) const {
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
    p = fit_params(m_, screen_, p, mask_of(effects, lens_), sigma_, opt_.screen_iterations);
    return {effects, p, bic(p, effects, screen_)};
  }

  // s without e, fitted on idx from s's values.
  State remove(const State& s, Effect e, const std::vector<int>& idx, int iterations) const {
    std::vector<Effect> effects;
    for (Effect f : s.effects)
      if (f != e) effects.push_back(f);
    ModelParams p = s.params;
    const ParamMask drop = effect_params(e, lens_);
    for (int k = 0; k < kParamCount; ++k)
      // With its followers (fy follows fx): a focal length withdrawn left fy 26% off on a real clip.
      if (drop[k]) set_param(p, static_cast<Param>(k), nominal_.v[k], m_.recording().nominal);
    if (e == Effect::ReadoutDirection) p.flip_readout = false;
    if (e == Effect::LensModel) p.other_lens = false;
    p = fit_params(m_, idx, p, mask_of(effects, lens_), sigma_, iterations);
    return {effects, p, bic(p, effects, idx)};
  }

  // lens_model: the other family's lens, starting from its nearest stand-in for the lens the
  // state has (over the image's field); it takes lens_distortion's place, whose terms it frees.
  void switch_lens(std::vector<Effect>& effects, ModelParams& p) const {
    const NominalModel& n = m_.recording().nominal;
    const Distortion now = lens_of(n, p);
    p.other_lens = true;
    set_lens_terms(p, nearest_lens(now, lens_family(n, p), field_));
    effects.erase(std::remove(effects.begin(), effects.end(), Effect::LensDistortion), effects.end());
  }

  State refit_all(const State& screened) const {
    const ModelParams p = fit_params(m_, fit_, screened.params, mask_of(screened.effects, lens_), sigma_, opt_.max_iterations);
    return {screened.effects, p, bic(p, screened.effects, fit_)};
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

  // Robust chi-square drop on the held-out observations from `poorer` to `richer` (0 when
  // nothing is held out).
  double heldout_drop(const State& poorer, const State& richer) const {
    if (held_.empty()) return 0;
    return robust_chi2(m_.residuals(poorer.params, held_), sigma_) - robust_chi2(m_.residuals(richer.params, held_), sigma_);
  }

  // Under the translation nuisance, whether `richer` predicts the held-out observations worse
  // than `poorer` with the nuisance off, as the final model is judged (diagnosis.cpp, the first
  // invariant), by over kWorseSigmas standard errors paired over the frame pairs (the parallax
  // left in moves a pair's residuals together). "" when not, or when there is no nuisance.
  std::string worse_with_parallax_because(const State& poorer, const State& richer) const {
    if (held_.empty() || !richer.params.translation_nuisance) return "";
    ModelParams a = poorer.params, b = richer.params;
    a.translation_nuisance = b.translation_nuisance = false;
    const std::vector<Eigen::Vector2d> ra = m_.residuals(a, held_), rb = m_.residuals(b, held_);
    std::vector<int> pair(held_.size());
    for (size_t k = 0; k < held_.size(); ++k) pair[k] = m_.frame_rank(held_[k]);
    const PairedChange c = paired_change(ra, rb, pair);
    if (!(c.t > kWorseSigmas)) return "";
    std::ostringstream why;
    why << "with the camera's translation left in, it predicts the held-out frames worse than without it ("
        << robust_stats(ra).rms_px << " -> " << robust_stats(rb).rms_px << " px RMS; " << c.t
        << " standard errors over " << c.groups << " frame pairs)";
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
  LensModel lens_;  // the nominal lens's family
  double field_;    // the largest angle off the axis the image sees (radians), through the nominal lens
};

// The screening subsample's BIC drop projected onto the fitting set: the chi-square drop grows
// with the number of observations, the penalty with its logarithm.
double projected_drop(const Selector& sel, const State& from, const State& to) {
  const double rho = static_cast<double>(sel.screen_.size()) / static_cast<double>(sel.fit_.size());
  const double k_from = sel.k_of(from), k_to = sel.k_of(to);
  const double prior_from = implausibility(from.params, from.effects), prior_to = implausibility(to.params, to.effects);
  const double chi2_drop = (from.bic - k_from * std::log(2.0 * sel.screen_.size()) - prior_from) -
                           (to.bic - k_to * std::log(2.0 * sel.screen_.size()) - prior_to);
  return chi2_drop / rho - (k_to - k_from) * std::log(2.0 * sel.fit_.size()) - (prior_to - prior_from);
}

// Hypotheses that explain the same structure (a mount rotation, a principal point and a lever
// arm across the optical axis in landmarks; a focal length and distortion; a gyro scale and a
// focal length in matches) are compared head to head: fitted on all fitting observations, the
// lowest BIC wins, and those within min_bic_drop of it are its rivals, which the data cannot
// tell from it.
struct RoundResult {
  double drop = 0, held_drop = 0;
  std::vector<Effect> rivals;
  // Winners the held-out frames refused in this round, in order, each with why.
  std::vector<std::pair<Effect, std::string>> refused;
};

// One forward round: every candidate screened on the subsample; those whose projected drop is
// near the best (near-degenerate hypotheses, e.g. a lever arm along the optical axis and a
// focal length, which the subsample cannot tell apart) are refitted on all fitting
// observations and the lowest BIC there wins. A winner the held-out frames refuse leaves the
// round (`out.refused`) and the next best is asked, from the same screening, so that a stand-in
// that wins on the fitting frames does not hide an effect the data hold. Returns false when
// nothing (left) clears the threshold.
bool forward_round(const Selector& sel, const std::vector<Effect>& candidates, State& s, RoundResult& out) {
  out.refused.clear();
  State here = s;
  here.bic = sel.bic(s.params, s.effects, sel.screen_);
  struct Candidate {
    double projected;
    Effect added;
    State state;
    std::optional<State> refitted;  // on all fitting observations, once asked for
  };
  std::vector<Candidate> screened;  // never moved once built: `order` ranks pointers to them
  std::vector<Effect> open;
  for (Effect e : candidates)
    // lens_model replaces lens_distortion (with the other family's terms): never the reverse.
    if (!s.has(e) && !(e == Effect::LensDistortion && s.has(Effect::LensModel))) open.push_back(e);
  const std::string stage = "screening " + std::to_string(open.size()) + " candidates (" +
                            std::to_string(s.effects.size()) + " named so far)";
  for (size_t k = 0; k < open.size(); ++k) {
    State c = sel.screen_add(s, open[k]);
    const double d = projected_drop(sel, here, c);
    screened.push_back({d, open[k], std::move(c), std::nullopt});
    if (sel.opt_.step) sel.opt_.step(stage, static_cast<int>(k + 1), static_cast<int>(open.size()));
  }
  std::vector<Candidate*> order;
  for (Candidate& c : screened) order.push_back(&c);
  std::sort(order.begin(), order.end(), [](const Candidate* a, const Candidate* b) { return a->projected > b->projected; });
  while (!order.empty()) {
    const double best_projected = order.front()->projected;
    if (best_projected < sel.opt_.min_bic_drop) return false;
    const double margin = 30 + 0.05 * best_projected;
    std::vector<Candidate*> near;
    for (Candidate* c : order) {
      if (c->projected < best_projected - margin) break;
      if (!c->refitted) c->refitted = sel.refit_all(c->state);
      near.push_back(c);
    }
    // Among hypotheses the data hardly tell apart, one with a value no real hardware has is
    // the stand-in: the lowest BIC of the plausible ones wins (a gyro scale 8% off came within
    // 1% of a lens's distortion under parallax, and, winning, ended the rounds).
    auto lower_bic = [](const Candidate* a, const Candidate* b) { return a->refitted->bic < b->refitted->bic; };
    std::vector<Candidate*> plausible;
    for (Candidate* c : near)
      if (beyond_hardware_because(c->refitted->params, c->added, sel.m_).empty()) plausible.push_back(c);
    Candidate* best = plausible.empty() ? *std::min_element(near.begin(), near.end(), lower_bic)
                                        : *std::min_element(plausible.begin(), plausible.end(), lower_bic);
    out.rivals.clear();
    for (const Candidate* c : near)
      if (c != best && c->refitted->bic - best->refitted->bic < sel.opt_.min_bic_drop) out.rivals.push_back(c->added);
    // The winner by BIC; accepted by the drop with the design effect (which is itself noisy
    // by a few percent, too much to rank near-degenerate candidates by).
    out.drop = sel.drop(s, *best->refitted);
    if (out.drop < sel.opt_.min_bic_drop) return false;
    // Its value must be one real hardware has. If not, and it is the strongest structure left
    // (the round's first winner), that structure is physics outside the table (a gyro bias of
    // half a radian per second stands in for parallax, a gyro scale for a gyro that clips): the
    // rounds end, since a weaker effect named now would stand in for the same structure (a
    // lens, a mount for the clipping gyro), and the remainder reports it. (Named, the stand-in
    // would also carry every later round's fit, to be withdrawn only at the end.) After a
    // refused winner it is another stand-in for what was refused (a focal length 40% off for a
    // lens the held-out frames do not have), and the round goes on to the next best.
    const std::string name = effect_name(best->added);
    const std::string beyond = beyond_hardware_because(best->refitted->params, best->added, sel.m_);
    // The held-out observations must agree: the effect predicts frames the fit never saw better;
    // and a parameter on its bound is not measured (a lens's k4 pushed to 1).
    out.held_drop = sel.heldout_drop(s, *best->refitted);
    std::string unnameable = unnameable_because(best->refitted->params, best->added, sel.m_);
    if (unnameable.empty()) unnameable = sel.fits_the_tail_because(s, *best->refitted);
    if (unnameable.empty()) unnameable = sel.worse_with_parallax_because(s, *best->refitted);
    const bool heldout_worse = !sel.held_.empty() && out.held_drop <= 0;
    if (!heldout_worse && unnameable.empty()) {
      s = std::move(*best->refitted);
      return true;
    }
    // Every reason that holds is said: a user reading only one would look in the wrong place.
    std::string why = name + " not named: " + unnameable;
    if (heldout_worse)
      why += (unnameable.empty() ? "" : "; and ") + std::string("it fits the fitting frames (BIC drop ") +
             std::to_string(std::lround(out.drop)) + ") and predicts the held-out frames worse than without it";
    const bool first = out.refused.empty();
    out.refused.emplace_back(best->added, why);
    if (!beyond.empty() && first) {
      if (sel.opt_.progress) sel.opt_.progress(out.refused.back().second + "; no weaker effect is named in its stead");
      return false;
    }
    if (sel.opt_.progress) sel.opt_.progress(out.refused.back().second);
    std::erase(order, best);
  }
  return false;
}

// Forward rounds until no candidate clears the threshold. What the held-out frames refused and
// no later round named goes to `withheld` (each round asks every candidate again: a refused
// effect may be named once another is in).
std::vector<SelectedEffect> forward(const Selector& sel, const std::vector<Effect>& candidates, State& s,
                                    std::vector<std::string>& withheld) {
  std::vector<SelectedEffect> steps;
  RoundResult r;
  std::vector<std::pair<Effect, std::string>> refused;  // the latest refusal of each effect
  auto remember = [&] {
    for (auto& f : r.refused) {
      auto it = std::find_if(refused.begin(), refused.end(), [&](const auto& g) { return g.first == f.first; });
      if (it == refused.end()) refused.push_back(f);
      else it->second = f.second;
    }
  };
  while (true) {
    const State before = s;
    const bool named = forward_round(sel, candidates, s, r);
    remember();
    if (!named) {
      for (const auto& f : refused)
        if (!s.has(f.first)) withheld.push_back(f.second);
      return steps;
    }
    const double rms = sel.rms(s.params);
    // An effect the round replaced (lens_model takes lens_distortion's place) leaves the list.
    steps.erase(std::remove_if(steps.begin(), steps.end(), [&](const SelectedEffect& st) { return !s.has(st.effect); }),
                steps.end());
    for (Effect e : s.effects) {
      if (before.has(e)) continue;
      steps.push_back({e, rms, r.drop, r.held_drop, r.rivals});
      if (sel.opt_.progress)
        sel.opt_.progress(std::string("named ") + effect_name(e) + " (BIC drop " + std::to_string(std::lround(r.drop)) + ")");
    }
  }
}

// The steps without effect e's (it left the selection).
void forget(std::vector<SelectedEffect>& steps, Effect e) {
  steps.erase(std::remove_if(steps.begin(), steps.end(), [&](const SelectedEffect& st) { return st.effect == e; }), steps.end());
}

// Drops any selected effect whose removal (with a refit of the rest) costs less BIC than
// the selection threshold: an earlier pick that later ones made redundant. Screened on the
// subsample, confirmed on the fitting set.
void backward(const Selector& sel, State& s, std::vector<SelectedEffect>& steps) {
  bool changed = true;
  while (changed && s.effects.size() > 1) {
    changed = false;
    State here = s;
    here.bic = sel.bic(s.params, s.effects, sel.screen_);
    for (Effect e : s.effects) {
      const double projected = projected_drop(sel, sel.remove(s, e, sel.screen_, sel.opt_.screen_iterations), here);
      if (projected >= sel.opt_.min_bic_drop + 30 + 0.05 * std::abs(projected)) continue;
      State c = sel.remove(s, e, sel.fit_, sel.opt_.max_iterations);
      if (sel.drop(c, s) >= sel.opt_.min_bic_drop) continue;
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
    State without = sel.remove(s, e, sel.fit_, sel.opt_.max_iterations);
    double time_drop = 0, rate_drop = 0, apart = 0;
    const bool holds = sel.consistent(without, s, time_drop, rate_drop, apart);
    for (SelectedEffect& st : steps)
      if (st.effect == e) st.blocked_time_drop = time_drop, st.blocked_rate_drop = rate_drop;
    if (holds) return std::nullopt;
    if (sel.opt_.progress)
      sel.opt_.progress(std::string("dropped ") + effect_name(e) + ": it does not hold on the blocked halves" +
                        (apart > kHalvesAgreeSigmas ? " (they put its value " + std::to_string(std::lround(apart)) + " sigmas apart)" : ""));
    return without;
  });
}

// Drops any selected effect whose value real hardware does not have, or that sits on its fit's
// bound (plausibility.hpp, unnameable_because), refitting the rest; the latest pick is judged
// first. What was dropped, and why, goes to `withheld`.
void plausible_only(const Selector& sel, State& s, std::vector<SelectedEffect>& steps, std::vector<std::string>& withheld) {
  drop_latest_first(s, steps, [&](Effect e) -> std::optional<State> {
    const std::string why = unnameable_because(s.params, e, sel.m_);
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
    State without = sel.remove(s, e, sel.fit_, sel.opt_.max_iterations);
    const double drop = sel.heldout_drop(without, s);
    for (SelectedEffect& st : steps)
      if (st.effect == e) st.heldout_given_others = drop;
    if (drop > 0) return std::nullopt;
    std::ostringstream why;
    why << effect_name(e) << " not named: given the others it does not improve the held-out prediction (their robust "
        << "chi-square is " << std::lround(-drop) << " higher with it)";
    withheld.push_back(why.str());
    if (sel.opt_.progress) sel.opt_.progress(withheld.back());
    return without;
  });
}

}  // namespace

Selection select_effects(const DiagnosisModel& m, const std::vector<int>& fit, const std::vector<int>& held,
                         const std::vector<int>& screen, const ModelParams& nominal, const ModelParams& start,
                         double sigma_px, const SelectionOptions& opt) {
  const Selector sel(m, fit, held, screen, nominal, start, sigma_px, opt);
  State s = sel.initial();
  std::vector<std::string> withheld;
  std::vector<SelectedEffect> steps = forward(sel, applicable_effects(m), s, withheld);
  backward(sel, s, steps);
  if (!opt.blocked_halves) return {steps, s.params, withheld};
  if (opt.progress && !steps.empty()) opt.progress("checking the named effects on blocked halves (time, angular rate)");
  const bool dropped = consistency(sel, s, steps);
  plausible_only(sel, s, steps, withheld);
  each_improves_held_out(sel, s, steps, withheld);
  return {steps, s.params, withheld, dropped};
}

Selection hold_on_blocked_halves(const DiagnosisModel& m, const std::vector<int>& fit, const std::vector<int>& held,
                                 const std::vector<int>& screen, const ModelParams& nominal, const ModelParams& start,
                                 double sigma_px, const SelectionOptions& opt, Selection chosen) {
  const Selector sel(m, fit, held, screen, nominal, start, sigma_px, opt);
  State s{{}, chosen.params, 0};
  for (const SelectedEffect& st : chosen.effects) s.effects.push_back(st.effect);  // one step per effect
  s.bic = sel.bic(s.params, s.effects, fit);
  if (opt.progress && !chosen.effects.empty()) opt.progress("checking the named effects on blocked halves (time, angular rate)");
  chosen.dropped_on_halves = consistency(sel, s, chosen.effects);
  plausible_only(sel, s, chosen.effects, chosen.withheld);
  each_improves_held_out(sel, s, chosen.effects, chosen.withheld);
  chosen.params = s.params;
  return chosen;
}

}  // namespace rsd::dsp
