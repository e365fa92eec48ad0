// End-to-end benchmark of the daemon's hot path: the simulated camera at 120 fps, 640x480, in
// real time, through capture -> stamp -> rectify -> publish (LCM memq://, one subscriber in this
// process), with the daemon's default pipeline and rectifier settings (queues of 2, grid from
// 32 px refined to 0.05 px, reference row in the middle, infinite depth unless --depth plane).
//
// Reports drops, latency from last row read to publish (p50, p99, max: the pipeline's own
// LatencyStats), CPU time (getrusage, user + sys, whole process: per frame and as % of one core)
// and C++ heap allocations per frame (global operator new counted), after a warm-up, and prints
// PASS/MISS per goal. It reports; it does not fail (exit status 0 unless it cannot run).
//
// The camera: the simulator's renderer is not part of rsd and may be too slow to render
// 640x480 at 120 fps (here it is: tens of ms per frame). The harness therefore renders a ring
// of --ring frames (and records the simulator's velocity feed) once, before the clock starts,
// and a small replaying CameraSource delivers them at the frame rate on CLOCK_MONOTONIC, each
// at the instant its last row would have been read, with fresh stamps and the recorded velocity
// re-stamped; so the CPU and latency measured are rsd's pipeline, not the simulator. If the
// renderer keeps up (mean render time under half the frame period) --source auto uses the live
// SimSource instead; --source sim / replay force one.
//
//   cmake --build build-perf --target bench_pipeline_latency && build-perf/tests/bench_pipeline_latency
//   options: --seconds 10 --warmup 2 --fps 120 --width 640 --height 480 --format mono8|rgb8|nv12|...
//            (--rgb: rgb8) --depth plane
//            --source auto|sim|replay --ring 32 --cpu N (pin the process to core N; default 0,
//            -1: not pinned)
//            --online: the online calibration's estimator on (observe), fed by the pipeline's
//            frame tap and the camera's gyro, a hand-held camera (no translation, turning about
//            changing axes: every value fitted, the mount rotation too); its thread's
//            share of a core is reported, its allocations (thread rsd-online) are not counted
//            (docs/online-calibration.md)
//            --lens equi: a 143-degree fisheye (pinhole-equi, f = 0.4 width) instead of the
//            60-degree pinhole, rectified in the same lens (issue 35)
#include <lcm/lcm.h>
#include <sched.h>
#include <sys/resource.h>
#include <time.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "dsp/core/image_planes.hpp"
#include "daemon/frame_rectifier.hpp"
#include "daemon/online_calibration.hpp"
#include "daemon/pipeline.hpp"
#include "drivers/sim_source.hpp"
#include "drivers/monotonic_clock.hpp"

#include "tests/support/allocation_counter.hpp"  // every C++ allocation of this process, counted

using namespace rsd;

namespace {

void sleep_until_ns(int64_t t_ns) {
  timespec ts{static_cast<time_t>(t_ns / 1000000000), static_cast<long>(t_ns % 1000000000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) != 0) {}
}

// The simulated camera, rendered once into a ring and replayed in real time.
class ReplaySource final : public drivers::CameraSource {
 public:
  ReplaySource(const drivers::SimSourceConfig& cfg, int ring) : sim_(cfg), ring_n_(ring) {}
  std::string name() const override { return "sim-replay"; }
  void open() override {
    sim_.open();
    std::vector<drivers::VelocitySample> recorded;
    sim_.set_velocity_sink([&recorded](const drivers::VelocitySample& s) { recorded.push_back(s); });
    const drivers::FrameFormat f = sim_.format();
    sim_.start();
    int64_t t0 = 0;
    const int64_t r0 = drivers::monotonic_ns();
    for (int i = 0; i < ring_n_; ++i) {
      ring_.emplace_back(f.width, f.height, f.format);
      drivers::FrameMeta m;
      while (sim_.capture(ring_.back().view(), m, std::chrono::milliseconds(1000)) != drivers::CaptureStatus::Frame) {}
      if (i == 0) t0 = m.first_row_ns;
    }
    render_ms_ = static_cast<double>(drivers::monotonic_ns() - r0) * 1e-6 / ring_n_;
    period_ns_ = static_cast<int64_t>(1e9 / sim_.config().fps + 0.5);
    cycle_ns_ = period_ns_ * ring_n_;
    for (const auto& s : recorded)
      if (s.t_ns - t0 >= 0 && s.t_ns - t0 < cycle_ns_) {
        velocity_.push_back(s);
        velocity_.back().t_ns = s.t_ns - t0;  // relative to the first frame's start
      }
    const dsp::RowTiming t = sim_.timing();
    ready_after_ns_ = static_cast<int64_t>((t.frame_readout_s() + t.exposure_s) * 1e9);
    velocity_period_ns_ = static_cast<int64_t>(1e9 / sim_.config().velocity_rate_hz + 0.5);
  }
  drivers::FrameFormat format() const override { return sim_.format(); }
  dsp::RowTiming timing() const override { return sim_.timing(); }
  void start() override {
    t0_ns_ = drivers::monotonic_ns() + 10'000'000;
    next_ = 0;
    lap_ = 0;
    vel_i_ = 0;
  }
  drivers::CaptureStatus capture(const dsp::ImageView& dst, drivers::FrameMeta& meta,
                                 std::chrono::milliseconds timeout) override {
    const int64_t ready = t0_ns_ + static_cast<int64_t>(next_) * period_ns_ + ready_after_ns_;
    int64_t now = drivers::monotonic_ns();
    if (ready - now > std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count()) {
      sleep_until_ns(now + std::chrono::duration_cast<std::chrono::nanoseconds>(timeout).count());
      return drivers::CaptureStatus::Timeout;
    }
    if (ready > now) sleep_until_ns(ready);
    now = drivers::monotonic_ns();
    // A real camera does not wait for a late reader: frames completed meanwhile are lost.
    const uint64_t latest = static_cast<uint64_t>((now - t0_ns_ - ready_after_ns_) / period_ns_);
    if (latest > next_) skipped_.fetch_add(latest - next_, std::memory_order_relaxed), next_ = latest;
    dsp::copy_image(ring_[next_ % ring_.size()].view(), dst);  // every plane (NV12's chroma too)
    meta.first_row_ns = t0_ns_ + static_cast<int64_t>(next_) * period_ns_;
    meta.sequence = next_;
    meta.exposure_s = sim_.timing().exposure_s;
    // As the live simulator does: through the frame's last row and one sample beyond, so that
    // the rectifier has the samples covering the frame without waiting (imu_wait_ms).
    emit_velocity_until(meta.first_row_ns + ready_after_ns_ + velocity_period_ns_);
    ++next_;
    return drivers::CaptureStatus::Frame;
  }
  void stop() override {}
  void set_velocity_sink(drivers::VelocitySink sink) override { sink_ = std::move(sink); }

  double render_ms() const { return render_ms_; }
  uint64_t skipped() const { return skipped_.load(std::memory_order_relaxed); }

 private:
  void emit_velocity_until(int64_t t_ns) {
    if (!sink_ || velocity_.empty()) return;
    for (;;) {
      drivers::VelocitySample s = velocity_[vel_i_];
      s.t_ns += t0_ns_ + static_cast<int64_t>(lap_) * cycle_ns_;
      if (s.t_ns > t_ns) return;
      sink_(s);
      if (++vel_i_ == velocity_.size()) vel_i_ = 0, ++lap_;
    }
  }
  drivers::SimSource sim_;
  int ring_n_;
  std::vector<dsp::Image> ring_;
  std::vector<drivers::VelocitySample> velocity_;
  drivers::VelocitySink sink_;
  double render_ms_ = 0;
  int64_t period_ns_ = 0, cycle_ns_ = 0, ready_after_ns_ = 0, t0_ns_ = 0, velocity_period_ns_ = 0;
  uint64_t next_ = 0, lap_ = 0;
  size_t vel_i_ = 0;
  std::atomic<uint64_t> skipped_{0};
};

struct Snapshot {
  uint64_t in = 0, out = 0, drops = 0, rectified = 0, skipped = 0, allocs = 0;
  double cpu_s = 0;
  int64_t wall_ns = 0;
};

double cpu_seconds() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

void on_image(const lcm_recv_buf_t*, const char*, void* user) {
  static_cast<std::atomic<uint64_t>*>(user)->fetch_add(1, std::memory_order_relaxed);
}

std::string cpu_model() {
  std::ifstream f("/proc/cpuinfo");
  for (std::string line; std::getline(f, line);)
    if (line.rfind("model name", 0) == 0) return line.substr(line.find(':') + 2);
  return "unknown";
}

std::string loadavg() {
  std::ifstream f("/proc/loadavg");
  std::string a, b, c;
  f >> a >> b >> c;
  return a + " " + b + " " + c;
}

int usage(const char* arg) {
  std::fprintf(stderr, "bench_pipeline_latency: bad argument '%s' (see the comment at the top of the source)\n", arg);
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10, warmup = 2, fps = 120;
  int width = 640, height = 480, ring = 32, cpu = 0;
  bool plane = false, online = false, fisheye = false;
  dsp::PixelFormat format = dsp::PixelFormat::Mono8;
  std::string source_mode = "auto";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has = i + 1 < argc;
    if (a == "--rgb") format = dsp::PixelFormat::Rgb8;
    else if (a == "--format" && has) {
      const auto f = dsp::parse_format_name(argv[++i]);
      if (!f) return usage(argv[i]);
      format = *f;
    }
    else if (a == "--seconds" && has) seconds = std::atof(argv[++i]);
    else if (a == "--warmup" && has) warmup = std::atof(argv[++i]);
    else if (a == "--fps" && has) fps = std::atof(argv[++i]);
    else if (a == "--width" && has) width = std::atoi(argv[++i]);
    else if (a == "--height" && has) height = std::atoi(argv[++i]);
    else if (a == "--ring" && has) ring = std::atoi(argv[++i]);
    else if (a == "--cpu" && has) cpu = std::atoi(argv[++i]);
    else if (a == "--source" && has) source_mode = argv[++i];
    else if (a == "--online") online = true;
    else if (a == "--lens" && has) fisheye = std::string(argv[++i]) == "equi";
    else if (a == "--depth" && has) {
      const std::string d = argv[++i];
      if (d != "plane" && d != "infinite") return usage(argv[i]);
      plane = d == "plane";
    } else return usage(argv[i]);
  }
  if (seconds <= 0 || fps <= 0 || width <= 0 || height <= 0 || ring <= 0 ||
      (source_mode != "auto" && source_mode != "sim" && source_mode != "replay"))
    return usage("values");

  if (cpu >= 0) {  // every thread started from here on inherits the mask
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(cpu, &set);
    if (sched_setaffinity(0, sizeof(set), &set) != 0) {
      std::perror("sched_setaffinity");
      return 2;
    }
  }

  drivers::SimSourceConfig sc;
  sc.camera = dsp::CameraModel::from_hfov(width, height, 60.0 * 3.14159265358979 / 180.0);
  if (fisheye) {  // BM_RectifyLens's fisheye
    sc.camera.fx = sc.camera.fy = 0.4 * width;
    sc.camera.dist = dsp::Distortion::equidistant(0.0469, -0.0135, 0.0021, -0.0003);
  }
  sc.fps = fps;
  sc.format = format;
  sc.realtime = true;
  if (online) {  // hand-held, turning about changing axes: the estimator fits every value, mount too
    sc.velocity = sc.angular_rate = Eigen::Vector3d::Zero();
    sc.wobble_rad_s = 0.8, sc.wobble_hz = 0.9;
    sc.wobble_axes = {1, 0.8, 0.5}, sc.wobble_axes_hz = {1, 1.37, 0.71};
  }
  drivers::SimSourceConfig render_cfg = sc;
  render_cfg.realtime = false;

  std::printf("pre-rendering %d frames %dx%d %s ...\n", ring, width, height, dsp::format_name(format));
  std::fflush(stdout);
  ReplaySource replay(render_cfg, ring);
  replay.open();
  const double period_ms = 1e3 / fps;
  const bool live = source_mode == "sim" || (source_mode == "auto" && replay.render_ms() < 0.5 * period_ms);
  std::unique_ptr<drivers::SimSource> sim;
  drivers::CameraSource* source = &replay;
  if (live) {
    sim = std::make_unique<drivers::SimSource>(sc);
    sim->open();
    source = sim.get();
  }

  daemon::VelocityBuffer velocity;
  const drivers::FrameFormat fmt = source->format();
  daemon::LcmPublisher pub("memq://", {}, fmt);
  std::unique_ptr<daemon::OnlineCalibrator> estimator;
  if (online) {
    daemon::OnlineSetup st;
    st.nominal.cam = sc.camera;
    st.nominal.frame_rate_hz = fps;
    st.nominal.time.line_delay_s = source->timing().line_delay_s;
    st.start = {0, st.nominal.time.line_delay_s, Eigen::Vector3d::Zero()};
    estimator = std::make_unique<daemon::OnlineCalibrator>(daemon::OnlineCalibrationConfig{}, st, pub);
  }
  source->set_velocity_sink([&velocity, &estimator](const drivers::VelocitySample& s) {
    velocity.push(s);
    if (estimator) estimator->gyro(s.t_ns / 1000, s.w);  // the camera's rates as an IMU would give them
  });
  daemon::RectifyConfig rc;  // the daemon's defaults
  if (plane) rc.depth = daemon::DepthKind::Plane, rc.depth_m = sc.scene_depth_m;
  daemon::FrameRectifier rectifier(rc, sc.camera, source->timing(), fmt);
  daemon::Pipeline pipeline(daemon::PipelineConfig{}, *source, rectifier, pub, velocity);
  std::atomic<uint64_t> received{0};
  lcm_subscribe(pub.handle(), "RSD_RECT", on_image, &received);

  const auto snap = [&]() {
    Snapshot s;
    const auto& st = pipeline.stats();
    s.in = st.frames_in.load();
    s.out = st.frames_out.load();
    s.drops = st.drops.load();
    s.rectified = st.rectified.load();
    s.skipped = live ? 0 : replay.skipped();
    s.allocs = g_allocations.load();
    s.cpu_s = cpu_seconds();
    s.wall_ns = drivers::monotonic_ns();
    return s;
  };
  // The main thread is the subscriber: it handles LCM until `until_ns`.
  const auto serve = [&](int64_t until_ns) {
    while (drivers::monotonic_ns() < until_ns) lcm_handle_timeout(pub.handle(), 5);
  };

  if (estimator) pipeline.set_frame_tap(estimator.get()), estimator->start();
  source->start();
  pipeline.start();
  serve(drivers::monotonic_ns() + static_cast<int64_t>(warmup * 1e9));
  const Snapshot a = snap();
  if (estimator) estimator->cpu_share();  // from here
  pipeline.latency().reset();
  serve(a.wall_ns + static_cast<int64_t>(seconds * 1e9));
  const Snapshot b = snap();
  const double p50 = pipeline.latency().quantile(0.5), p99 = pipeline.latency().quantile(0.99),
               pmax = pipeline.latency().max_ms();
  const double estimator_share = estimator ? estimator->cpu_share() : 0;
  const dsp::OnlineEstimate estimate = estimator ? estimator->latest() : dsp::OnlineEstimate{};
  pipeline.stop();
  source->stop();
  if (estimator) estimator->stop();
  while (lcm_handle_timeout(pub.handle(), 0) > 0) {}

  const double wall_s = static_cast<double>(b.wall_ns - a.wall_ns) * 1e-9;
  const uint64_t out = b.out - a.out, drops = (b.drops - a.drops) + (b.skipped - a.skipped);
  const double expected = wall_s * fps;
  const double cpu_s = b.cpu_s - a.cpu_s;
  const double allocs_per_frame = out ? static_cast<double>(b.allocs - a.allocs) / static_cast<double>(out) : 0;
  const auto verdict = [](bool ok) { return ok ? "PASS" : "MISS"; };

  std::printf("\nEnd to end: %dx%d %s, %.0f fps, depth %s, camera: %s\n", width, height, dsp::format_name(format), fps,
              plane ? "plane (3 m)" : "infinite (rotation only)",
              live ? "live SimSource (realtime)" : "simulator frames pre-rendered, replayed in real time");
  std::printf("simulator render time %.1f ms/frame (frame period %.2f ms)\n", replay.render_ms(), period_ms);
  std::printf("CPU: %s; pinned to %s; load average %s\n", cpu_model().c_str(),
              cpu >= 0 ? ("core " + std::to_string(cpu)).c_str() : "no core", loadavg().c_str());
  std::printf("measured %.1f s after %.1f s warm-up: %llu frames published of %.0f expected, %llu rectified, "
              "%llu received by the subscriber since start\n\n",
              wall_s, warmup, static_cast<unsigned long long>(out), expected,
              static_cast<unsigned long long>(b.rectified - a.rectified),
              static_cast<unsigned long long>(received.load()));
  std::printf("%-38s %12s %10s %6s\n", "metric", "value", "goal", "");
  std::printf("%-38s %12llu %10s %6s\n", "drops (pipeline + camera)", static_cast<unsigned long long>(drops), "0",
              verdict(drops == 0));
  std::printf("%-38s %12.2f %10s %6s\n", "latency p50 (ms, last row -> publish)", p50, "-", "");
  std::printf("%-38s %12.2f %10s %6s\n", "latency p99 (ms)", p99, "<= 1", verdict(p99 <= 1.0));
  std::printf("%-38s %12.2f %10s %6s\n", "latency max (ms)", pmax, "-", "");
  std::printf("%-38s %12.3f %10s %6s\n", "CPU per frame (ms, user+sys)", out ? 1e3 * cpu_s / static_cast<double>(out) : 0,
              "-", "");
  std::printf("%-38s %12.1f %10s %6s\n", "CPU (% of one core)", 100.0 * cpu_s / wall_s, "-", "");
  std::printf("%-38s %12.3f %10s %6s\n", "allocations per frame (operator new)", allocs_per_frame, "0",
              verdict(b.allocs == a.allocs));
  // Issue 36's goal is at 30 fps; at higher rates the estimator still takes 15 frames a second,
  // but shares its core with a busier hot path (reported, not judged).
  const bool judged = fps <= 30;
  if (estimator)
    std::printf("%-38s %12.1f %10s %6s\n%-38s %12s %10s %6s\n", "online estimator (% of one core)", 100 * estimator_share,
                judged ? "<= 10" : "-", judged ? verdict(estimator_share <= 0.10) : "", "online estimate",
                dsp::to_string(estimate.state), "-", "");
  return 0;
}
