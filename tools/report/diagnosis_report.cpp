#include "tools/report/diagnosis_report.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "tools/common/cli_util.hpp"
#include "tools/report/diagnosis_figures.hpp"
#include "dsp/diagnosis/select.hpp"

namespace rsd::tools {

using namespace rsd::dsp;
namespace fs = std::filesystem;

namespace {

std::string nominal_value(const NominalModel& n, const std::string& name);

// ---------------------------------------------------------------- a page per named effect

// The fitted model without one named effect (its parameters back at their nominal values).
ModelParams without(const Diagnosis& d, const NominalModel& n, const std::string& name) {
  ModelParams p = d.fitted;
  const ModelParams nom = nominal_params(n);
  for (int k = 0; k < static_cast<int>(Effect::Count); ++k) {
    if (effect_name(Effect(k)) != name) continue;
    const ParamMask mask = effect_params(Effect(k), n.cam.dist.model);
    for (int j = 0; j < kParamCount; ++j)
      if (mask[j]) p.v[j] = nom.v[j];
    if (Effect(k) == Effect::ReadoutDirection) p.flip_readout = false;
    if (Effect(k) == Effect::LensModel) p.other_lens = false;
  }
  return p;
}

std::string drop_text(double v) { return std::isnan(v) ? std::string("-") : format_number(v, 4); }

std::string effect_page(const Figures& f, const Diagnosis& d, const NamedEffect& e, const NominalModel& n,
                        double removed_rms, const std::string& figure) {
  std::ostringstream o;
  o << "# Named effect: `" << e.name << "`\n\n" << e.explains << ".\n\n"
    << "| parameter | fitted | 1-sigma | nominal |\n| --- | --- | --- | --- |\n";
  for (const ParamUncertainty& p : d.uncertainties)
    if (p.effect == e.name)
      o << "| `" << p.param << "` | " << (p.text.empty() ? format_number(p.value, 6) : p.text) << " | "
        << (p.sigma ? format_number(*p.sigma, 3) : std::string("-")) << " | " << nominal_value(n, p.param) << " |\n";
  o << "\n| evidence | value |\n| --- | --- |\n"
    << "| BIC drop when it was added (threshold 10) | " << format_number(e.bic_drop, 4) << " |\n"
    << "| held-out robust chi-square drop (every " << kHeldoutEvery << "th frame, unseen by the fit) | "
    << format_number(e.heldout_drop, 4) << " |\n"
    << "| blocked halves in time: chi-square drop on the unseen half (worse direction) | " << drop_text(e.blocked_time_drop)
    << " |\n"
    << "| blocked halves in angular rate: drop on the unseen half (worse direction) | " << drop_text(e.blocked_rate_drop)
    << " |\n"
    << "| RMS of the residual structure it removes (per coordinate) | " << format_number(removed_rms, 4) << " px |\n"
    << "| fitting-set RMS once it was in | " << format_number(e.rms_px, 4) << " px |\n\n";
  if (!e.rivals.empty()) {
    o << "**The data cannot tell it from";
    for (size_t k = 0; k < e.rivals.size(); ++k) o << (k ? " or " : " ") << "`" << e.rivals[k] << "`";
    o << "**: head to head on all fitting observations their BIC came within the threshold of this one's.\n\n";
  }
  o << "![What " << e.name << " removes, and the final residual](" << figure << ")\n\n"
    << "Left: the mean, per image cell, of the residual the model leaves without this effect (the other named "
       "effects at their fitted values) minus the final residual: the structure this effect explains. Right: the "
       "final residual. Sigma " << format_number(f.sigma, 3) << " px.\n\n[Back to the diagnosis](index.md)\n";
  return o.str();
}

// ---------------------------------------------------------------- index.md

std::string verdict(const Diagnosis& d) {
  std::ostringstream o;
  if (d.effects.empty()) {
    o << "**Verdict: the recording agrees with its nominal model within its noise.** No named effect is "
         "supported by the data.";
  } else {
    o << "**Verdict: the nominal model does not fit; " << d.effects.size() << " named effect"
      << (d.effects.size() > 1 ? "s explain" : " explains") << " the difference:";
    for (size_t k = 0; k < d.effects.size(); ++k) o << (k ? ", " : " ") << "`" << d.effects[k].name << "`";
    o << ".**";
  }
  if (d.remainder.significant)
    o << " **Structure beyond noise remains that no named effect explains (see What remains).**";
  o << " Held-out RMS " << format_number(d.heldout_baseline_rms_px) << " px (nominal) -> "
    << format_number(d.heldout_final_rms_px) << " px (final";
  if (d.heldout_nominal.translation_nuisance)
    o << "; each held-out frame pair's translation taken out, as the effects were fitted; with the parallax in "
      << format_number(d.heldout_with_parallax_baseline_rms_px) << " -> " << format_number(d.heldout_with_parallax_final_rms_px)
      << " px";
  o << "); the residual sigma noise alone gives: " << format_number(d.sigma_px) << " px";
  if (!d.sigma_restarts.empty()) {
    o << " (the selection started at";
    for (size_t k = 0; k < d.sigma_restarts.size(); ++k) o << (k ? ", then " : " ") << format_number(d.sigma_restarts[k], 3) << " px";
    o << ", ended far from it and ran again at the scale it ended with)";
  }
  o << ".\n";
  return o.str();
}

std::string nominal_value(const NominalModel& n, const std::string& name) {
  if (name == "frame_readout_s") return format_number(n.time.line_delay_s * n.cam.height, 6);
  if (name == "direction") return std::string(to_string(n.time.readout));
  if (const auto k = param_by_name(name)) return format_number(nominal_params(n)[*k], 6);
  return "";
}

std::string effects_table(const Diagnosis& d, const std::vector<ParamUncertainty>& u, const NominalModel& n) {
  std::ostringstream o;
  if (d.effects.empty()) return "None: the nominal model fits within the noise.\n";
  o << "| effect | parameter | fitted | 1-sigma | nominal |\n| --- | --- | --- | --- | --- |\n";
  for (const ParamUncertainty& p : u)
    o << "| `" << p.effect << "` | `" << p.param << "` | " << (p.text.empty() ? format_number(p.value, 6) : p.text)
      << " | " << (p.sigma ? format_number(*p.sigma, 3) : std::string("-")) << " | " << nominal_value(n, p.param)
      << " |\n";
  o << "\n| effect (order selected; its page) | explains | fitting-set RMS with it (px) | BIC drop | held-out "
       "chi-square drop | blocked halves: time, rate |\n| --- | --- | --- | --- | --- | --- |\n";
  for (const NamedEffect& e : d.effects)
    o << "| [`" << e.name << "`](effect-" << e.name << ".md) | " << e.explains << " | " << format_number(e.rms_px)
      << " | " << format_number(e.bic_drop) << " | " << format_number(e.heldout_drop) << " | "
      << drop_text(e.blocked_time_drop) << ", " << drop_text(e.blocked_rate_drop) << " |\n";
  return o.str();
}

std::string remainder_section(const Remainder& r) {
  std::ostringstream o;
  o << "## What remains\n\n" << (r.significant ? "**Significant: physics the effect table does not hold.** " : "")
    << r.summary << "\n\n"
    << "| test | statistic | z | structured RMS (px) |\n| --- | --- | --- | --- |\n"
    << "| across each frame: differences with a far observation over differences with the nearest one outside "
       "its tracking window (1 = noise) | "
    << format_number(r.spatial_ratio, 3) << " | " << format_number(r.spatial_z, 3) << " | "
    << format_number(r.spatial_rms_px, 3) << " |\n"
    << "| from frame to frame: von Neumann ratio of the frame means (1 = independent frames) | "
    << format_number(r.temporal_ratio, 3) << " | " << format_number(r.temporal_z, 3) << " | "
    << format_number(r.temporal_rms_px, 3) << " |\n"
    << "| whole frames: frames mostly outliers, " << r.lost_frames << " of " << r.tested_frames << " (mismatches alone "
    << "would make " << format_number(r.lost_expected, 3) << "); statistic: the share of the observations in them | "
    << format_number(r.lost_share, 3) << " | " << format_number(r.lost_z, 3) << " | - |\n\n"
    << "Structure is called significant when a test is clear (z above 4) and material (its variance at least a "
       "fifth of the noise's; whole frames: a twentieth of the observations in them).\n";
  o << "\n![The final residual per frame: mean and RMS over time](remainder.png)\n";
  if (!r.located.empty()) {
    o << "\n| where the remainder lives | strength | detail |\n| --- | --- | --- |\n";
    for (const Located& l : r.located)
      o << "| `" << l.signal << "` | " << format_number(l.strength, 3) << " | " << l.detail << " |\n";
  }
  return o.str();
}

std::string index_markdown(const ReportInput& in, const std::vector<ParamUncertainty>& u) {
  const Diagnosis& d = *in.diagnosis;
  const NominalModel& n = in.model->recording().nominal;
  std::ostringstream o;
  o << "# Diagnosis of `" << in.recording_dir << "`\n\n" << verdict(d) << "\n";
  o << "| residual RMS (px, per coordinate, inliers) | nominal model | final model |\n| --- | --- | --- |\n"
    << "| held out: " << d.heldout_observations << " observations of every " << in.heldout_every
    << "th frame, not used by the fit" << (d.heldout_nominal.translation_nuisance ? " (each pair's translation taken out)" : "")
    << " | " << format_number(d.heldout_baseline_rms_px) << " | " << format_number(d.heldout_final_rms_px) << " |\n";
  if (d.heldout_nominal.translation_nuisance)
    o << "| held out, the parallax in | " << format_number(d.heldout_with_parallax_baseline_rms_px) << " | "
      << format_number(d.heldout_with_parallax_final_rms_px) << " |\n";
  for (size_t h = 0; h < d.heldout_halves.size(); ++h)
    o << "| held out, " << (h ? "second" : "first") << " half in time: " << d.heldout_halves[h].observations
      << " observations | " << format_number(d.heldout_halves[h].baseline_rms_px) << " | "
      << format_number(d.heldout_halves[h].final_rms_px) << " |\n";
  o << "| all " << d.baseline.observations << " observations | " << format_number(d.baseline.rms_px) << " | "
    << format_number(d.final_rms_px) << " |\n\n"
    << "The named effects' values were fitted on " << d.fit_observations << " fitting observations (chosen by the "
    << "information they carry when there were more than the fits need; with a parallax's translation taken out, up "
    << "to three times those the effects were chosen on).\n\n"
    << "Outliers of the nominal model (beyond " << kOutlierSigmas << " robust sigmas, or no prediction): "
    << d.baseline.outliers << ". Diagnosis took " << format_number(in.seconds, 3) << " s.\n\n";
  o << "## Named effects\n\n" << effects_table(d, u, n) << "\n";
  if (!d.candidates.empty()) {
    o << "Effects considered for this recording:";
    for (size_t k = 0; k < d.candidates.size(); ++k) o << (k ? ", " : " ") << "`" << d.candidates[k] << "`";
    o << " (an effect is named when the evidence for it, BIC, is very strong).\n\n";
  }
  o << "Uncertainties: 1-sigma from the fit's numeric Jacobian J over the fitting-set inliers, all named "
       "effects' parameters free together (correlations widen them): the larger of the classic s^2 (J^T J)^-1 "
       "(s the per-coordinate RMS of those residuals) and the sandwich estimate clustered by frame, which also "
       "sees errors a frame's observations share (gyro noise, stamp jitter). With a camera's translation taken "
       "out (parallax), the clock offset's also holds, in quadrature, how far the minimum of its profile (the "
       "translation fitted afresh at each offset) lies from the fit's value and, where the scene's depths spread, "
       "how far it moves under the other depth model (one plane, or each match's own depth). They hold if the "
       "named effects are the whole story.\n\n";
  o << "## Where the residual lives (nominal model)\n\n";
  if (d.located.empty()) o << "No structured residual (no signal explains 5% of it).\n";
  else o << "| signal | strength | detail |\n| --- | --- | --- |\n";
  for (const Located& l : d.located)
    o << "| `" << l.signal << "` | " << format_number(l.strength, 3) << " | " << l.detail << " |\n";
  o << "\n" << remainder_section(d.remainder);
  o << "\n## Figures\n\nTop panels: the nominal model; bottom: the final one. Pixel positions are "
    << (in.model->recording().kind == ObservationKind::Matches ? "frame_b's (the predicted end of each match)"
                                                               : "the observed landmarks'")
    << "; outliers are left out.\n\n"
    << "![Residual against image row](residual-vs-row.png)\n\n"
    << "![Residual against radius](residual-vs-radius.png)\n\n"
    << "![Residual against time](residual-vs-time.png)\n\n"
    << "![Residual map](residual-map.png)\n";
  return o.str();
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
  if (!f) throw std::runtime_error(path.string() + ": cannot write");
}

}  // namespace

std::vector<std::string> write_report(const std::string& report_dir, const ReportInput& in) {
  const DiagnosisModel& m = *in.model;
  const Diagnosis& d = *in.diagnosis;
  const fs::path dir(report_dir);
  fs::create_directories(dir);
  const Figures f = figures_of(m, d);
  std::vector<std::string> files;
  auto png = [&](const std::string& name) { return files.emplace_back((dir / name).string()); };
  residual_vs_figure(f, png("residual-vs-row.png"), f.row, "image row", "image row v (px)");
  residual_vs_figure(f, png("residual-vs-radius.png"), f.radius, "radius", "distance from the principal point (px)");
  residual_vs_figure(f, png("residual-vs-time.png"), f.time, "time", "frame time since the first frame (s)");
  residual_map_figure(f, png("residual-map.png"));
  remainder_figure(f, d.remainder, png("remainder.png"));
  const NominalModel& n = m.recording().nominal;
  for (const NamedEffect& e : d.effects) {
    const Residuals removed = removed_by(f, without(d, n, e.name));
    const std::string fig = "effect-" + e.name + ".png";
    effect_figure(f, removed, e.name, png(fig));
    write_text(dir / ("effect-" + e.name + ".md"), effect_page(f, d, e, n, rms_of(removed), fig));
    files.push_back((dir / ("effect-" + e.name + ".md")).string());
  }
  write_text(dir / "index.md", index_markdown(in, d.uncertainties));
  files.push_back((dir / "index.md").string());
  return files;
}

}  // namespace rsd::tools
