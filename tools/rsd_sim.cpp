// rsd-sim: simulates rolling-shutter cameras.
//
//   rsd-sim recording SCENARIO.yaml OUTDIR   observation recording (recording-v1)
//   rsd-sim frames SCENARIO.yaml OUTDIR      rendered PNG frames of the scenario's target
//   rsd-sim lcm SCENARIO.yaml OUT.lcmlog     raw frames + true velocity (+ body pose) as an LCM log
//   rsd-sim images SCENARIO.yaml OUTDIR      an images recording: PNG frames, trajectory, target
//   rsd-sim figure1 OUTDIR                   the paper's Figure 1 (rotating checkerboard)
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "tools/common/cli_util.hpp"
#include "dsp/sim/recording_simulation.hpp"
#include "dsp/sim/rs_renderer.hpp"
#include "formats/image_file.hpp"
#include "formats/recording_v1.hpp"
#include "tools/sim/scenario_frames.hpp"
#include "tools/sim/sim_lcm_log.hpp"
#include "formats/scenario_file.hpp"

namespace formats = rsd::formats;
using namespace rsd;
namespace fs = std::filesystem;

namespace {

using tools::FrameOptions;
using tools::FrameRig;
using tools::make_rig;

int run_recording(const std::string& scenario, const std::string& out) {
  const formats::Scenario sc = formats::load_scenario(scenario);
  const auto t0 = std::chrono::steady_clock::now();
  const dsp::SimulatedRecording sim = dsp::simulate_recording(sc.sim);
  formats::write_recording(out, sim.rec);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto& r = sim.rec;
  std::printf("rsd-sim: wrote %s recording to %s in %.2f s\n", dsp::to_string(r.kind), out.c_str(), secs);
  std::printf("  %zu frames at %.3g fps, %zu %s, %zu %s samples, noise %.3g px\n", r.frames.size(),
              r.nominal.frame_rate_hz,
              r.kind == dsp::ObservationKind::Landmarks ? r.observations.size() : r.matches.size(),
              r.kind == dsp::ObservationKind::Landmarks ? "observations" : "matches",
              r.motion == dsp::MotionKind::Trajectory ? r.trajectory.size() : r.gyro.size(),
              dsp::to_string(r.motion), sc.sim.noise_px);
  const auto names = sim.truth.names();
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  std::printf("  effects the nominal model leaves out: %s\n", names.empty() ? "none" : list.c_str());
  return 0;
}

void progress(size_t k, size_t n) {
  std::fprintf(stderr, "\rrsd-sim: frame %zu/%zu", k + 1, n);
  if (k + 1 == n) std::fprintf(stderr, "\n");
}

int run_frames(const std::string& scenario, const std::string& out, const FrameOptions& o) {
  FrameRig rig = make_rig(scenario, o);
  fs::create_directories(out);
  const dsp::CameraModel& cam = rig.truth.cam;
  dsp::Image img(cam.width, cam.height, o.rgb ? dsp::PixelFormat::Rgb8 : dsp::PixelFormat::Mono8);
  for (size_t k = 0; k < rig.frames; ++k) {
    rig.renderer->render(rig.scene, *rig.motion, rig.sim.rec.frames[k].t, img.view());
    char name[64];
    std::snprintf(name, sizeof name, "frame_%06d.png", rig.sim.rec.frames[k].frame);
    formats::write_png((fs::path(out) / name).string(), img.view());
    progress(k, rig.frames);
  }
  std::printf("rsd-sim: wrote %zu frames (%dx%d, line delay %.3g s, %s) to %s\n", rig.frames, cam.width, cam.height,
              rig.truth.time.line_delay_s, dsp::to_string(rig.truth.time.readout).data(), out.c_str());
  return 0;
}

int run_lcm(const std::string& scenario, const std::string& out, const FrameOptions& o) {
  FrameRig rig = make_rig(scenario, o);
  std::vector<double> times;
  for (size_t k = 0; k < rig.frames; ++k) times.push_back(rig.sim.rec.frames[k].t);
  const tools::SimLogSpec spec{out, rig.timing, 200.0};
  tools::SimPoseLog poses;
  if (o.pose) poses.poses = rig.sim.rec.trajectory;  // world = the target's frame, motion clock
  tools::write_sim_lcm_log(spec, times, rig.truth.cam.width, rig.truth.cam.height,
                           o.rgb ? dsp::PixelFormat::Rgb8 : dsp::PixelFormat::Mono8,
                           [&](size_t k, const dsp::ImageView& v) {
                             rig.renderer->render(rig.scene, *rig.motion, times[k], v);
                             progress(k, times.size());
                           },
                           *rig.motion, poses);
  std::printf("rsd-sim: wrote %zu raw frames on %s and the true velocity at 200 Hz on %s to %s\n", times.size(),
              tools::kRawChannel, tools::kVelocityChannel, out.c_str());
  if (o.pose)
    std::printf("  and %zu body poses at %.4g Hz on %s\n", poses.poses.size(), rig.sc.sim.trajectory_rate_hz,
                tools::kPoseChannel);
  return 0;
}

// The paper's Figure 1: a fronto-parallel checkerboard 0.5 m away, 40 degree field of
// view, 30 fps with the readout filling the frame, rotating about the optical axis.
int run_images(const std::string& scenario, const std::string& out, const FrameOptions& o) {
  const FrameRig rig = make_rig(scenario, o);
  tools::write_images_recording(rig, o, out);
  std::printf("rsd-sim: wrote an images recording (%zu frames as PNG, %zu poses, the target and its %zu points) to %s\n",
              rig.frames, rig.sim.rec.trajectory.size(), rig.sim.rec.points.size(), out.c_str());
  const auto names = rig.sim.truth.names();
  std::string list;
  for (const auto& n : names) list += (list.empty() ? "" : ", ") + n;
  std::printf("  effects its nominal model leaves out: %s\n", names.empty() ? "none" : list.c_str());
  return 0;
}

int run_figure1(const std::string& out) {
  fs::create_directories(out);
  const dsp::CameraModel cam = dsp::CameraModel::from_hfov(640, 480, 40.0 * M_PI / 180.0);
  const dsp::RowTiming timing = dsp::RowTiming::full_frame(480, 30);
  dsp::Scene scene;
  scene.planes.push_back(dsp::fronto_parallel_checkerboard(0.5, 10, 8, 0.025));  // 25 x 20 cm, all in view
  scene.background = Eigen::Vector3f::Ones();
  dsp::RenderOptions ro;
  ro.supersample = 4;
  dsp::RsRenderer renderer(cam, timing, ro);
  dsp::Image img(cam.width, cam.height, dsp::PixelFormat::Mono8);
  const char* names[] = {"quarter", "half", "three-quarters", "one"};
  for (int i = 0; i < 4; ++i) {
    const double rev_per_s = 0.25 * (i + 1);
    dsp::Twist tw;
    tw.w = Eigen::Vector3d(0, 0, 2 * M_PI * rev_per_s);
    renderer.render(scene, dsp::ScrewMotion(tw), 0.0, img.view());
    const std::string file = (fs::path(out) / (std::string("figure1-") + names[i] + "-rev-per-s.png")).string();
    formats::write_png(file, img.view());
    std::printf("rsd-sim: %s (%.2f rev/s about the optical axis)\n", file.c_str(), rev_per_s);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rsd-sim: simulate rolling-shutter cameras (recordings, frames, the paper's figure 1).\n"
               "Scenario files are YAML; see docs/simulator.md and config/scenarios/."};
  app.require_subcommand(1);
  std::string scenario, out;
  FrameOptions fo;
  // What every rendering subcommand takes: how many frames, and how each is rendered.
  auto add_picture_options = [&fo](CLI::App* sub) {
    sub->add_option("--count", fo.count, "frames to render (default: all)")->check(CLI::NonNegativeNumber);
    sub->add_flag("--rgb", fo.rgb, "RGB frames instead of mono8");
    sub->add_option("--noise", fo.noise, "pixel noise sigma in grey levels")->check(CLI::NonNegativeNumber);
    sub->add_option("--supersample", fo.supersample, "n x n samples per pixel (anti-aliasing; 1 takes a quarter of the default's samples)")
        ->check(CLI::Range(1, 8))
        ->capture_default_str();
  };
  auto* rec = app.add_subcommand("recording", "write an observation recording (docs/formats/recording-v1.md)");
  rec->add_option("scenario", scenario, "scenario YAML")->required()->check(CLI::ExistingFile);
  rec->add_option("outdir", out, "output directory (created)")->required();
  auto* frames = app.add_subcommand("frames", "render the scenario's target as PNG frames, each row at its read time");
  frames->add_option("scenario", scenario, "scenario YAML (landmarks kind)")->required()->check(CLI::ExistingFile);
  frames->add_option("outdir", out, "output directory (created)")->required();
  add_picture_options(frames);
  frames->add_option("--exposure", fo.exposure_s, "row exposure in s (motion blur)")->check(CLI::NonNegativeNumber);
  frames->add_option("--blur-samples", fo.blur_samples, "time samples over the exposure")->check(CLI::Range(1, 64));
  auto* lcmlog = app.add_subcommand("lcm", "write raw frames and the true velocity as an LCM log (rsd's replay input)");
  lcmlog->add_option("scenario", scenario, "scenario YAML (landmarks kind)")->required()->check(CLI::ExistingFile);
  lcmlog->add_option("log", out, "output .lcmlog file")->required();
  add_picture_options(lcmlog);
  lcmlog->add_option("--exposure", fo.exposure_s, "row exposure in s (motion blur)")->check(CLI::NonNegativeNumber);
  lcmlog->add_option("--blur-samples", fo.blur_samples, "time samples over the exposure")->check(CLI::Range(1, 64));
  lcmlog->add_flag("--pose", fo.pose,
                   "also write the body's pose (world = the target's frame, motion clock) as bot_core.pose_t on RSD_POSE, "
                   "like motion capture (rsd-extract's landmarks input)");
  auto* images = app.add_subcommand("images", "write an images recording: the frames as PNG with the body trajectory, the "
                                               "target and its points (what rsd --replay DIR and rsd-diagnose DIR read)");
  images->add_option("scenario", scenario, "scenario YAML (landmarks kind, checkerboard or aprilgrid)")->required()->check(CLI::ExistingFile);
  images->add_option("outdir", out, "output directory (created)")->required();
  add_picture_options(images);
  auto* fig = app.add_subcommand("figure1", "render the paper's Figure 1 (four PNGs)");
  fig->add_option("outdir", out, "output directory (created)")->required();
  if (const auto rc = tools::parse_command_line(app, argc, argv)) return *rc;
  return tools::run_tool("rsd-sim", [&] {
    if (*rec) return run_recording(scenario, out);
    if (*frames) return run_frames(scenario, out, fo);
    if (*lcmlog) return run_lcm(scenario, out, fo);
    if (*images) return run_images(scenario, out, fo);
    return run_figure1(out);
  });
}
