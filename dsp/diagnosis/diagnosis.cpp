#include "dsp/diagnosis/diagnosis.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <sstream>
#include <utility>

#include "dsp/diagnosis/blocked_halves.hpp"
#include "dsp/diagnosis/heldout_check.hpp"
#include "dsp/diagnosis/observation_choice.hpp"
#include "dsp/diagnosis/offset_search.hpp"
#include "dsp/diagnosis/own_depth.hpp"
#include "dsp/diagnosis/select.hpp"
#include "dsp/diagnosis/stabiliser.hpp"
#include "dsp/diagnosis/uncertainty.hpp"

namespace rsd::dsp {

namespace {

NamedEffect describe(const SelectedEffect& st, const ModelParams& p, const NominalModel& n) {
  NamedEffect out{effect_name(st.effect), {}, "", st.rms_px, st.bic_drop, st.heldout_drop,
                  st.blocked_time_drop, st.blocked_rate_drop, {}};
  for (Effect r : st.rivals) out.rivals.push_back(effect_name(r));
  std::ostringstream x;
  auto param = [&](Param q) { return EffectParam{param_name(q), p[q], ""}; };
  switch (st.effect) {
    case Effect::RollingShutter: {
      const double readout = p[Param::LineDelay] * n.cam.height;
      out.params = {param(Param::LineDelay), {"frame_readout_s", readout, ""}};
      x << "rows are read over " << readout * 1e3 << " ms, not " << n.time.line_delay_s * n.cam.height * 1e3 << " ms";
      break;
    }
    case Effect::TimeOffset:
      out.params = {param(Param::TimeOffset)};
      x << "the motion clock is " << p[Param::TimeOffset] * 1e3 << " ms ahead of the camera clock";
      break;
    case Effect::ReadoutDirection: {
      const bool down = (n.time.readout == Readout::TopToBottom) != p.flip_readout;
      out.params = {{"direction", 0, down ? "top_to_bottom" : "bottom_to_top"}};
      x << "rows are read " << (down ? "top to bottom" : "bottom to top") << ", not the nominal order";
      break;
    }
    case Effect::ClockDrift:
      out.params = {param(Param::Drift)};
      x << "the camera clock runs " << p[Param::Drift] << " ppm slow against the motion clock";
      break;
    case Effect::LensDistortion:
    case Effect::LensModel: {
      const LensModel family = lens_family(n, p);
      const bool equi = family == LensModel::PinholeEqui;
      if (st.effect == Effect::LensModel) out.params.push_back({"model", 0, lens_model_name(family)});
      for (Param q : {Param::K1, Param::K2, Param::K3, Param::K4})
        if (equi || q == Param::K1 || q == Param::K2) out.params.push_back(param(q));
      if (st.effect == Effect::LensModel)
        x << "the lens is " << (equi ? "an equidistant (fisheye) lens" : "a pinhole lens with radial distortion") << ", not "
          << lens_model_name(n.cam.dist.model) << ": ";
      else
        x << "radial distortion ";
      x << "k1 = " << p[Param::K1] << ", k2 = " << p[Param::K2];
      if (equi) x << ", k3 = " << p[Param::K3] << ", k4 = " << p[Param::K4];
      break;
    }
    case Effect::FocalLength:
      out.params = {param(Param::Fx), param(Param::Fy)};
      x << "focal length " << p[Param::Fx] << " x " << p[Param::Fy] << " px, not " << n.cam.fx << " x " << n.cam.fy;
      break;
    case Effect::GyroBias:
      out.params = {param(Param::BiasX), param(Param::BiasY), param(Param::BiasZ)};
      x << "the gyro reads (" << p[Param::BiasX] * 1e3 << ", " << p[Param::BiasY] * 1e3 << ", "
        << p[Param::BiasZ] * 1e3 << ") mrad/s too much (IMU axes)";
      break;
    case Effect::LeverArm:
      out.params = {param(Param::LeverX), param(Param::LeverY), param(Param::LeverZ)};
      x << "the camera sits at (" << p[Param::LeverX] * 1e3 << ", " << p[Param::LeverY] * 1e3 << ", "
        << p[Param::LeverZ] * 1e3 << ") mm in body axes";
      break;
    case Effect::MountRotation: {
      out.params = {param(Param::MountX), param(Param::MountY), param(Param::MountZ)};
      const double deg = Eigen::Vector3d(p[Param::MountX], p[Param::MountY], p[Param::MountZ]).norm() * 180 / M_PI;
      x << "the camera is turned by " << deg << " degrees on its mount against the motion sensor";
      break;
    }
    case Effect::GyroScale:
      out.params = {param(Param::ScaleX), param(Param::ScaleY), param(Param::ScaleZ)};
      x << "the gyro's scale is (" << p[Param::ScaleX] << ", " << p[Param::ScaleY] << ", " << p[Param::ScaleZ]
        << ") of what it reads (IMU axes)";
      break;
    case Effect::PrincipalPoint:
      out.params = {param(Param::Cx), param(Param::Cy)};
      x << "the principal point is (" << p[Param::Cx] << ", " << p[Param::Cy] << ") px, not (" << n.cam.cx << ", " << n.cam.cy << ")";
      break;
    case Effect::Count: break;
  }
  if (!out.rivals.empty()) {
    x << "; the data cannot tell it from";
    for (size_t k = 0; k < out.rivals.size(); ++k) x << (k ? " or " : " ") << out.rivals[k];
    x << " (head to head, BIC within the threshold)";
  }
  out.explains = x.str();
  return out;
}

// Fitting and held-out observations: whole frames are held out, every n-th in time order.
void split(const DiagnosisModel& m, int every, std::vector<int>& fit, std::vector<int>& held) {
  for (int i = 0; i < m.size(); ++i)
    (held_out(m, i, every) ? held : fit).push_back(i);
}

// Every continuous parameter of the applicable effects (lens_model's terms are the nominal
// lens's here: its switch stays off).
ParamMask applicable_params(const DiagnosisModel& m) {
  ParamMask all;
  for (Effect e : applicable_effects(m))
    if (e != Effect::LensModel) all |= effect_params(e, m.recording().nominal.cam.dist.model);
  return all;
}

// Without a stated noise: the robust scale once every applicable continuous effect is fitted
// at once (from the gross start), on the screening subsample. In matches whose richest
// rotation-only fit still shows parallax (judged on `fit_set`), the scale is that of the same
// fit with each frame pair's translation taken out, and the parallax is returned with it: a
// selection at the rotation-only scale would end far below it and run again, and the parallax
// it would find sends it to the translation nuisance anyway.
struct ScaleEstimate {
  double sigma_px;
  Parallax parallax;
};
ScaleEstimate estimate_sigma(const DiagnosisModel& m, const std::vector<int>& screen, const std::vector<int>& fit_set,
                             const ModelParams& gross, double guess) {
  const ParamMask all = applicable_params(m);
  ModelParams rich = fit_params(m, screen, gross, all, guess, 20);
  const Parallax parallax = parallax_signal(m, rich, fit_set);
  if (parallax.clear()) {
    rich.translation_nuisance = true;
    rich = fit_params(m, screen, rich, all, guess, 20);
  }
  return {std::max(robust_stats(m.residuals(rich, screen)).scale_px, 1e-3), parallax};
}

// The gross search (gross_start); in matches whose richest rotation-only fit from its result
// (every applicable effect at once: a lens or a rolling shutter left out would look like a
// translation) shows parallax, run again with the translation nuisance on: a near scene's flow,
// a few pixels in every pair, would otherwise steer the search (a forward flight's flow moved a
// 10 ms offset to 0.38 s and the focal length by 20%). That parallax is kept in `parallax`.
ModelParams gross_search(const DiagnosisModel& m, const std::vector<int>& screen, const std::vector<int>& fit_set,
                         const ModelParams& nominal, double sigma, Parallax& parallax, const DiagnosisOptions& opt) {
  auto step = [&](const char* stage) -> std::function<void(int, int)> {
    if (!opt.step) return nullptr;
    return [&opt, stage](int done, int total) { opt.step(stage, done, total); };
  };
  const ModelParams plain = gross_start(m, screen, nominal, sigma, step("searching the clock offset at each focal scale"));
  if (m.kind() != ObservationKind::Matches) return plain;
  const ModelParams rich = fit_params(m, screen, plain, applicable_params(m), sigma, 20);
  const Parallax px = parallax_signal(m, rich, fit_set);
  if (!px.clear()) return plain;
  parallax = px;
  ModelParams n = nominal;
  n.translation_nuisance = true;
  return gross_start(m, screen, n, sigma, step("searching again with the translation taken out"));
}

// Where the residual lives. A gross error (a clock offset of a large fraction of a second, a
// focal length several percent off) swamps every linear pattern, so when the global search
// moved the offset or the focal length, that is reported first, with the share of the
// residual energy it removes, and the patterns then describe what remains after it.
std::vector<Located> locate_with_gross(const DiagnosisModel& m, const ModelParams& nominal, const ModelParams& gross,
                                       const std::vector<int>& fit) {
  const double offset = gross[Param::TimeOffset] - nominal[Param::TimeOffset];
  const double scale = gross[Param::Fx] / nominal[Param::Fx] - 1;
  // Gross: beyond a frame period (a rolling shutter alone shifts features by up to half of
  // one, and the row pattern describes that) or 2% of the focal length.
  const double gross_offset = 1.0 / m.recording().nominal.frame_rate_hz;
  if (std::abs(offset) < gross_offset && std::abs(scale) < 0.02) return locate(m, nominal, fit);
  const std::vector<int> sub = subsample(fit, 3000);
  const double before = robust_stats(m.residuals(nominal, sub)).rms_px, after = robust_stats(m.residuals(gross, sub)).rms_px;
  const double share = before > 0 ? std::clamp(1 - (after * after) / (before * before), 0.0, 1.0) : 0.0;
  std::vector<Located> out;
  std::ostringstream d;
  if (std::abs(offset) >= gross_offset) {
    d << "a global search for the clock offset moves the motion clock by " << offset * 1e3 << " ms and removes "
      << std::lround(share * 100) << "% of the residual energy";
    out.push_back({"image_velocity", share, d.str()});
  }
  if (std::abs(scale) >= 0.02) {
    d.str("");
    d << "a global search for the focal length scales it by " << scale * 100 << "%";
    out.push_back({"image_scale", out.empty() ? share : 0.0, d.str()});
  }
  for (Located l : locate(m, gross, fit)) {
    l.detail += " (what remains after the global search)";
    out.push_back(std::move(l));
  }
  return out;
}

// The observations of idx that the gyro covers (no gap longer than max_gyro_gap).
std::vector<int> usable(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx) {
  std::vector<int> out;
  for (int i : idx)
    if (m.gyro_gap(p, i) <= m.max_gyro_gap()) out.push_back(i);
  return out;
}

// The translation nuisance's knot spacing (translation_knot_spacing), whether its plane is fixed
// in the world (translation_travel) and the scene's depth spread about it
// (translation_depth_spread), judged on the richest rotation fit from `gross` under the nuisance,
// every applicable effect free: what an effect explains is not left for a finer spline to take,
// nor measured as the scene's depths. Set in `n` and `gross`.
void nuisance_shape(const DiagnosisModel& m, const std::vector<int>& screen, ModelParams& n, ModelParams& gross,
                    double sigma) {
  n.translation_nuisance = gross.translation_nuisance = true;
  ModelParams richest = fit_params(m, screen, gross, applicable_params(m), sigma, 20);
  richest.translation_knot_s = n.translation_knot_s = gross.translation_knot_s =
      translation_knot_spacing(m, screen, richest);
  richest.translation_world_plane = n.translation_world_plane = gross.translation_world_plane =
      translation_travel(m, screen, richest) < kWorldPlaneTravel;
  const double spread = translation_depth_spread(m, screen, richest);
  n.translation_depth_px = gross.translation_depth_px = own_depth_px(sigma, spread);
}

// The selection without the translation nuisance, its blocked-halves check held until the
// parallax test (`seen`) has run on its residuals: checking stand-ins that will not be kept
// would be wasted. Nothing when the residuals show parallax.
std::optional<Selection> select_without_parallax(const DiagnosisModel& m, const std::vector<int>& use_fit,
                                                 const std::vector<int>& use_held, const std::vector<int>& screen,
                                                 const ModelParams& nominal, const Diagnosis& d, const SelectionOptions& so,
                                                 Parallax& seen) {
  SelectionOptions first = so;
  first.blocked_halves = false;
  ModelParams g = d.gross;
  g.translation_nuisance = false;
  Selection sel = select_effects(m, use_fit, use_held, screen, nominal, g, d.sigma_px, first);
  seen = parallax_signal(m, sel.params, use_fit);
  // A stabiliser found (a gain stood in for the pictures following the gyro smoothed) leaves a
  // rotation the gyro does not carry, which the parallax test takes for a translation over a
  // narrow field and the nuisance would take up: a 1 Hz stabiliser's remainder was said to be
  // parallax. The selection that found it stands.
  if (seen.clear() && !sel.stabiliser_sigma_s) return std::nullopt;
  return hold_on_blocked_halves(m, use_fit, use_held, screen, nominal, g, d.sigma_px, so, sel);
}

// The observations a selection fits on and holds out, and the candidates' screening subset.
struct ObservationSets {
  std::vector<int> fit, held, screen;
};

// Under the translation nuisance the named effects' values come from a final fit on up to this
// many times DiagnosisOptions::fit_observations. The choice by leverage weighs a frame pair's
// observations for the effects alone; under the nuisance part of what they carry goes to the
// velocity spline, which every pair shares, and which part the choice cannot tell. A drone
// flying past a scene 40 m ahead (the suite's, 71 542 observations) had its 20 ms readout -5.1%
// to +1.0% over seven seeds from the 30 000 chosen, -2.0% to +0.7% from all of them
// (docs/diagnosis.md). Which effects are named is decided on the budget alone: each decision
// refits on every fitting observation, and a minute's walk has 200 000.
constexpr size_t kTranslationBudgetFactor = 3;

// The named effects' values fitted again on `wide` (under the translation nuisance more fitting
// observations than the selection decided on), from the selection's.
Selection refit_on(const DiagnosisModel& m, const std::vector<int>& wide, double sigma_px, const SelectionOptions& so,
                   Selection chosen) {
  if (chosen.effects.empty()) return chosen;
  std::vector<Effect> named;
  for (const SelectedEffect& st : chosen.effects) named.push_back(st.effect);
  if (so.progress) so.progress("the named effects' values fitted on " + std::to_string(wide.size()) + " observations");
  chosen.params = fit_params(m, wide, chosen.params, mask_of(named, m.recording().nominal.cam.dist.model), sigma_px,
                             so.max_iterations);
  return chosen;
}

// The selection; for matches with parallax the rotation-only model cannot express, chosen again
// on what a translation per frame pair cannot explain, so that no effect stands in for it, and
// the named effects' values fitted again on the fitting observations `under_translation` gives.
// The parameters keep the translation nuisance on when it was used.
Selection select_with_parallax(const DiagnosisModel& m, const ObservationSets& sets,
                               const std::function<const std::vector<int>&()>& under_translation, const ModelParams& nominal,
                               Diagnosis& d, const SelectionOptions& so) {
  const std::vector<int>&use_fit = sets.fit, &use_held = sets.held, &screen = sets.screen;
  // The gross search's parallax did not hold at the noise scale: the selection without the
  // nuisance, unless its residuals show parallax. A restart (at another sigma) after parallax
  // was found goes straight to the selection under the nuisance.
  const bool seen_before_any_effect = d.parallax.clear();
  // Or it did, and the gross state follows the gyro smoothed better than a gain under one: a
  // stabiliser's misfit, which the parallax test takes for a translation over a narrow field (the
  // suite's stabilised clip on seed 0), and which the selection without the nuisance can find.
  if (!seen_before_any_effect || smoothing_beats_a_gain(m, screen, d.gross, d.sigma_px, so.min_bic_drop))
    if (auto plain = select_without_parallax(m, use_fit, use_held, screen, nominal, d, so, d.parallax)) return *plain;
  ModelParams n = nominal, g = d.gross;
  nuisance_shape(m, screen, n, g, d.sigma_px);
  if (so.progress) {
    std::ostringstream what;
    what << "parallax in the matches: selecting again with the camera's translation (a smooth velocity over the depth, knots every "
         << g.translation_knot_s << " s; "
         << (g.translation_world_plane ? "a scene fixed in the world, " : "a scene that keeps its distance, ")
         << (g.translation_depth_px > 0 ? "each match's depth its own" : "one plane")
         << ") taken out";
    so.progress(what.str());
  }
  Selection with = select_effects(m, use_fit, use_held, screen, n, g, d.sigma_px, so);
  if (!with.effects.empty() || !with.dropped_on_halves || !seen_before_any_effect)
    return refit_on(m, under_translation(), d.sigma_px, so, std::move(with));
  // Nothing named under the nuisance, because the blocked halves dropped the stand-ins it chose,
  // and the parallax was seen with no effect in: what the rotation-only model lacked (a rolling
  // shutter's shear, beside matches displaced in a part of the image) may have looked like
  // parallax, and under the nuisance a translation over a tilted scene takes up part of a
  // shutter's shear. The selection without the nuisance is kept if its residuals show no
  // parallax. (Where nothing was chosen at all, nothing hints that the nuisance hid an effect:
  // the real recordings' parallax, whose second selection cost twice the first's.)
  if (so.progress) so.progress("nothing named with the translation taken out: selecting again without it");
  Parallax after;
  auto plain = select_without_parallax(m, use_fit, use_held, screen, nominal, d, so, after);
  if (!plain) return with;
  d.parallax = after;
  return *plain;
}

}  // namespace

Diagnosis diagnose(const Recording& rec, const DiagnosisOptions& opt) { return diagnose(DiagnosisModel(rec), opt); }

ModelParams heldout_model(const Diagnosis& d, ModelParams p) {
  return d.heldout_nominal.translation_nuisance ? with_translation_of(std::move(p), d.heldout_nominal) : p;
}

Diagnosis diagnose(const DiagnosisModel& m, const DiagnosisOptions& opt) {
  const Recording& rec = m.recording();
  Diagnosis d;
  std::vector<int> all(m.size()), fit, held;
  for (int i = 0; i < m.size(); ++i) all[i] = i;
  split(m, opt.heldout_every, fit, held);
  const size_t n_screen = static_cast<size_t>(std::max(opt.screen_observations, 100));
  const ModelParams nominal = nominal_params(rec.nominal);
  d.baseline = robust_stats(m.residuals(nominal, all));
  for (Effect e : applicable_effects(m)) d.candidates.push_back(effect_name(e));
  d.noise_floor_px = rec.noise_px ? *rec.noise_px * m.noise_gain() : 0.0;
  // Gross errors first, with the stated noise or a first guess of it (the baseline's scale).
  const double guess = d.noise_floor_px > 0 ? d.noise_floor_px : std::max(d.baseline.scale_px, 1e-3);
  auto progress = [&](const std::string& what) {
    if (opt.progress) opt.progress(what);
  };
  progress("searching the clock offset and focal scale for gross errors");
  const std::vector<int> fit_screen = subsample(fit, n_screen);
  d.gross = gross_search(m, fit_screen, fit, nominal, guess, d.parallax, opt);
  // The fits see at most opt.fit_observations of the usable fitting observations (and a
  // quarter as many held out), chosen by the information they carry at the gross start.
  std::vector<int> use_all, use_fit, use_held;
  ObservationSets sets;
  std::optional<std::vector<int>> wide;  // under the translation nuisance, chosen when first asked
  const ParamMask every = applicable_params(m);
  const size_t budget = static_cast<size_t>(std::max(opt.fit_observations, 0));
  auto split_usable = [&] {
    use_all = usable(m, d.gross, all), use_fit = usable(m, d.gross, fit), use_held = usable(m, d.gross, held);
    ObservationChoice fit_choice{budget};
    if (m.kind() == ObservationKind::Matches) fit_choice.run = kMatchesRunFrames;
    sets.fit = choose_observations(m, use_fit, d.gross, every, fit_choice);
    sets.held = choose_observations(m, use_held, d.gross, every, {budget / 4});
    sets.screen = subsample(sets.fit, n_screen);
    wide.reset();
  };
  const std::function<const std::vector<int>&()> under_translation = [&]() -> const std::vector<int>& {
    if (!wide) {
      ObservationChoice wide_choice{kTranslationBudgetFactor * budget};
      wide_choice.run = kMatchesRunFrames;
      wide = choose_observations(m, use_fit, d.gross, every, wide_choice);
    }
    return *wide;
  };
  const std::vector<int>&fit_set = sets.fit, &screen = sets.screen;
  split_usable();
  // The gross start's offset settled at the noise's scale (settle_time_offset), the
  // observations chosen again where it moved.
  auto settle_offset = [&] {
    const double settled = settle_time_offset(m, screen, d.gross, d.sigma_px);
    if (settled == d.gross[Param::TimeOffset]) return;
    d.gross[Param::TimeOffset] = settled;
    split_usable();
  };
  if (fit_set.size() < use_fit.size())
    progress("fitting on " + std::to_string(fit_set.size()) + " of the " + std::to_string(use_fit.size()) +
             " fitting observations, chosen by the information they carry");
  // Without a stated noise the scale comes from the data once the gross errors are in; a
  // search run at a guess far off (fast motion: the baseline's scale is tens of pixels) is
  // run again at the scale it led to.
  if (d.noise_floor_px > 0) {
    d.sigma_px = d.noise_floor_px;
  } else {
    ScaleEstimate e = estimate_sigma(m, screen, fit_set, d.gross, guess);
    if (std::abs(std::log(e.sigma_px / guess)) > std::log(1.25)) {
      d.gross = gross_search(m, fit_screen, fit, nominal, e.sigma_px, d.parallax, opt);
      split_usable();
      e = estimate_sigma(m, screen, fit_set, d.gross, e.sigma_px);
    }
    d.sigma_px = e.sigma_px, d.parallax = e.parallax;
  }
  settle_offset();
  SelectionOptions so;
  so.min_bic_drop = opt.min_bic_drop, so.max_iterations = opt.max_iterations;
  so.progress = opt.progress;
  so.step = opt.step;
  Selection sel;
  for (int attempt = 0;; ++attempt) {
    progress("selecting effects at sigma " + std::to_string(d.sigma_px) + " px");
    sel = select_with_parallax(m, sets, under_translation, nominal, d, so);
    // The scale the fit ends with must agree with the one it started from (within 25%): a
    // recording that understates its noise, or a scale estimated before the effects were in,
    // would make BIC name noise. Otherwise the selection runs again at the scale it ended with.
    const double ended = robust_stats(m.residuals(sel.params, screen)).scale_px;
    const bool disagrees = ended > 1.25 * d.sigma_px || (d.noise_floor_px == 0 && ended < 0.8 * d.sigma_px);
    // With a stabiliser found the scale it ends with is the stabiliser's misfit, not noise:
    // selected again at it, a 1 Hz stabiliser's gain was no longer told from its smoothing.
    if (!disagrees || attempt == 2 || sel.stabiliser_sigma_s) break;
    d.sigma_restarts.push_back(d.sigma_px);
    d.sigma_px = ended;
    if (d.noise_floor_px == 0) {
      d.gross = gross_search(m, fit_screen, fit, nominal, d.sigma_px, d.parallax, opt);
      split_usable();
      settle_offset();
    }
  }
  // A stabilised clip whose misfit no gain took up (nothing under one was proposed, so the
  // Selector never asked): the final model through the gyro smoothed (a GoPro MAX's walk, its
  // video stabilised in the camera: robust chi-square 40% lower at 0.3 s).
  // What that selection named was never asked to beat the smoothing: selected again with it as
  // the bar from the first round, as every candidate is once the Selector has found a stabiliser.
  if (!sel.stabiliser_sigma_s && m.kind() == ObservationKind::Matches) {
    progress("asking whether the pictures follow the gyro smoothed (a video stabilised in the camera)");
    const std::optional<double> found =
        stabiliser_after_selection(m, screen, fit_set, sel.params, d.sigma_px, so.min_bic_drop);
    if (found && !sel.effects.empty()) {
      progress("a stabiliser found after the selection: selecting again, every effect asked to beat the smoothing");
      so.stabilised_s = found;
      sel = select_with_parallax(m, sets, under_translation, nominal, d, so);
    }
    if (!sel.stabiliser_sigma_s) sel.stabiliser_sigma_s = found;  // else the smoothing it refused effects by
  }
  // The uncertainties are the fit's: with the translation taken out as the effects were fitted
  // (left in, the parallax widened a drone's readout sigma tenfold over its seeds' scatter).
  const ModelParams as_fitted = sel.params;
  sel.params.translation_nuisance = false;  // what the named effects predict, parallax and all
  d.gross.translation_nuisance = false;  // the report's global search: what it moved, parallax and all
  d.located = locate_with_gross(m, nominal, d.gross, fit);
  d.unusable = m.size() - static_cast<int>(use_all.size());
  for (const SelectedEffect& st : sel.effects) d.effects.push_back(describe(st, sel.params, rec.nominal));
  d.fitted = sel.params;
  d.final_rms_px = robust_stats(m.residuals(sel.params, use_all)).rms_px;
  d.heldout_indices = use_held;
  d.heldout_observations = static_cast<int>(use_held.size());
  const auto heldout_rms = [&](const ModelParams& p) { return robust_stats(m.residuals(p, use_held)).rms_px; };
  d.heldout_nominal = as_fitted.translation_nuisance ? with_translation_of(nominal, as_fitted) : nominal;
  d.heldout_with_parallax_baseline_rms_px = heldout_rms(nominal);
  d.heldout_with_parallax_final_rms_px = heldout_rms(sel.params);
  d.heldout_baseline_rms_px = as_fitted.translation_nuisance ? heldout_rms(d.heldout_nominal) : d.heldout_with_parallax_baseline_rms_px;
  d.heldout_final_rms_px =
      as_fitted.translation_nuisance ? heldout_rms(heldout_model(d, sel.params)) : d.heldout_with_parallax_final_rms_px;
  d.withheld = sel.withheld;
  check_heldout(m, nominal, use_all, use_held, d);
  progress("uncertainties and the remainder");
  const std::vector<int>& fitted_on = as_fitted.translation_nuisance ? under_translation() : fit_set;
  d.uncertainties = effect_uncertainties(m, d.effects, as_fitted, fitted_on);
  std::vector<Effect> named;
  for (const SelectedEffect& st : sel.effects) named.push_back(st.effect);
  widen_offset_sigma(m, fitted_on, as_fitted, mask_of(named, rec.nominal.cam.dist.model), d.sigma_px, so.max_iterations,
                     d.uncertainties);
  d.fit_observations = static_cast<int>(fitted_on.size());
  const bool offset_named = std::any_of(sel.effects.begin(), sel.effects.end(),
                                        [](const SelectedEffect& st) { return st.effect == Effect::TimeOffset; });
  d.remainder = assess_remainder(m, d.fitted, use_all, d.noise_floor_px, robust_stats(m.residuals(nominal, use_all)).rms_px,
                                 sel.stabiliser_sigma_s, offset_named);
  for (const std::string& w : d.withheld) d.remainder.summary += (d.remainder.summary.empty() ? "" : "\n") + w + ".";
  return d;
}

}  // namespace rsd::dsp
