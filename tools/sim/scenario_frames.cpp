#include "tools/sim/scenario_frames.hpp"

#include <cstdio>
#include <filesystem>

#include "formats/image_file.hpp"
#include "formats/recording_v1.hpp"
#include "tools/common/cli_util.hpp"

namespace rsd::tools {

namespace fs = std::filesystem;

namespace {

std::vector<dsp::SampledTrajectory::Sample> samples(const dsp::Recording& r) {
  std::vector<dsp::SampledTrajectory::Sample> s;
  for (const auto& p : r.trajectory) s.push_back({p.t, p.q, p.p});
  return s;
}

}  // namespace

TrueCameraMotion::TrueCameraMotion(const dsp::Recording& r, const dsp::TrueModel& m) : m_(m), body_(samples(r)) {}

Eigen::Affine3d TrueCameraMotion::at(double t) const {
  Eigen::Affine3d g = body_.at(m_.time.motion_time(t));
  g.translation() -= m_.lever_arm;
  g.linear() = m_.mount.transpose() * g.linear();
  g.translation() = m_.mount.transpose() * g.translation();
  return g;
}

FrameRig make_rig(const std::string& scenario, const FrameOptions& o) {
  FrameRig rig;
  rig.sc = formats::load_scenario(scenario);
  if (rig.sc.sim.kind != dsp::ObservationKind::Landmarks)
    throw tools::UsageError(scenario + ": frames are rendered for landmarks scenarios (a target or point set)");
  rig.sc.sim.noise_px = 0;
  rig.sim = dsp::simulate_recording(rig.sc.sim);
  rig.truth = dsp::true_model(rig.sim.rec.nominal, rig.sc.sim.effects);
  rig.timing = dsp::row_timing(rig.truth.time, rig.truth.cam.height);
  rig.timing.frame_rate_hz = rig.sim.rec.nominal.frame_rate_hz;
  rig.timing.exposure_s = o.exposure_s;
  dsp::RenderOptions ro;
  ro.supersample = o.supersample;
  ro.exposure_samples = o.blur_samples;
  ro.noise_sigma = o.noise;
  ro.noise_seed = rig.sc.sim.seed;
  rig.renderer = std::make_unique<dsp::RsRenderer>(rig.truth.cam, rig.timing, ro);
  rig.motion = std::make_unique<TrueCameraMotion>(rig.sim.rec, rig.truth);
  rig.scene = rig.sc.target.scene;
  rig.frames = o.count > 0 ? std::min<size_t>(o.count, rig.sim.rec.frames.size()) : rig.sim.rec.frames.size();
  return rig;
}

void write_images_recording(const FrameRig& rig, const FrameOptions& o, const std::string& out) {
  if (rig.sc.target_spec.kind == dsp::TargetKind::Points)
    throw UsageError(rig.sc.file + ": an images recording needs a target a detector can find (checkerboard or aprilgrid)");
  formats::ImagesRecording rec;
  rec.rec = rig.sim.rec;
  rec.rec.observations.clear();
  rec.rec.frames.resize(rig.frames);
  rec.target = rig.sc.target_spec;
  const fs::path dir = fs::path(out) / "frames";
  fs::create_directories(dir);
  const dsp::CameraModel& cam = rig.truth.cam;
  dsp::Image img(cam.width, cam.height, o.rgb ? dsp::PixelFormat::Rgb8 : dsp::PixelFormat::Mono8);
  for (size_t k = 0; k < rig.frames; ++k) {
    const dsp::FrameStamp& f = rec.rec.frames[k];
    rig.renderer->render(rig.scene, *rig.motion, f.t, img.view());
    char name[32];
    std::snprintf(name, sizeof name, "%06d.png", f.frame);
    formats::write_png((dir / name).string(), img.view());
    rec.files.push_back((dir / name).string());
    std::fprintf(stderr, "\rrsd-sim: frame %zu/%zu", k + 1, rig.frames);
  }
  std::fprintf(stderr, "\n");
  formats::write_images_recording(out, rec);
}

}  // namespace rsd::tools
