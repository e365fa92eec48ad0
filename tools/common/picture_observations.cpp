#include "tools/common/picture_observations.hpp"

#include <opencv2/imgproc.hpp>

#include <malloc.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <set>
#include <stdexcept>

#include "drivers/images_source.hpp"
#include "dsp/diagnosis/observation_choice.hpp"
#include "dsp/features/target_observations.hpp"
#include "tools/common/progress_line.hpp"

namespace rsd::tools {

std::vector<bool> covered_by_motion(const std::vector<double>& frame_t, double motion_t0, double motion_t1,
                                    const dsp::NominalModel& nominal, double margin_s) {
  std::vector<bool> ok;
  for (const double t : frame_t) {
    const double tm = t + nominal.time.time_offset_s;
    ok.push_back(tm - margin_s >= motion_t0 && tm + 1.0 / nominal.frame_rate_hz + margin_s <= motion_t1);
  }
  return ok;
}

cv::Mat grey8(const dsp::Image& img, double& scale16) {
  const cv::Mat m(img.height, img.width,
                  img.format == dsp::PixelFormat::Mono8 ? CV_8UC1 : img.format == dsp::PixelFormat::Rgb8 ? CV_8UC3 : CV_16UC1,
                  const_cast<uint8_t*>(img.data.data()), static_cast<size_t>(img.stride()));
  cv::Mat g;
  if (m.type() == CV_8UC1) g = m.clone();
  else if (m.type() == CV_8UC3) cv::cvtColor(m, g, cv::COLOR_RGB2GRAY);
  else {
    if (scale16 <= 0) {
      double mx = 0;
      cv::minMaxLoc(m, nullptr, &mx);
      scale16 = mx > 0 ? 255.0 / mx : 1.0 / 256;
    }
    m.convertTo(g, CV_8U, scale16);
  }
  return g;
}

namespace {

cv::Mat next_grey(PictureFrames& f, size_t k, double& scale16) {
  std::optional<dsp::Image> img = f.next();
  if (!img) throw std::runtime_error(f.what + ": frame " + std::to_string(f.numbers[k]) + " could not be read");
  return grey8(*img, scale16);
}

// Reads past frame k without converting it.
void skip(PictureFrames& f, size_t k) {
  if (!f.next()) throw std::runtime_error(f.what + ": frame " + std::to_string(f.numbers[k]) + " could not be read");
}

// The tracker and OpenCV free and allocate each frame's picture and pyramids (megabytes at
// 1080p) every frame; by default glibc hands such blocks back to the kernel at once, and every
// frame's pages then fault in again, zeroed: 40% of a 1080p log's extraction went to the kernel.
// A batch tool keeps them for reuse instead (process-wide; the tools only).
void keep_freed_memory() {
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 512 << 20);
}

// The pairs (k-1, k) to track (chosen[k]), and a line saying so when they are not all.
std::vector<bool> pairs_to_track(const PictureFrames& f, const dsp::Recording& rec, size_t max_pairs) {
  std::vector<double> t = f.times;
  if (t.size() != f.numbers.size()) t.assign(f.numbers.size(), 0.0);  // no stamps: the even share
  const std::vector<bool> chosen = dsp::choose_frame_pairs(t, f.usable, rec.gyro, rec.nominal.time.time_offset_s, max_pairs);
  size_t usable = 0, taken = 0;
  for (size_t k = 1; k < chosen.size(); ++k) usable += f.usable[k - 1] && f.usable[k], taken += chosen[k];
  if (taken < usable)
    std::printf("rsd: tracking %zu of %zu frame pairs, chosen by the gyro's rates and evenly (--track-pairs)\n", taken, usable);
  return chosen;
}

// Only the frames of tracked pairs stay in rec.frames.
void keep_tracked_frames(const PictureFrames& f, const std::vector<bool>& chosen, dsp::Recording& rec) {
  std::set<int> tracked;
  for (size_t k = 1; k < chosen.size(); ++k)
    if (chosen[k]) tracked.insert(f.numbers[k - 1]), tracked.insert(f.numbers[k]);
  std::vector<dsp::FrameStamp> kept;
  for (const dsp::FrameStamp& s : rec.frames)
    if (tracked.count(s.frame)) kept.push_back(s);
  rec.frames = kept;
}

}  // namespace

void make_matches(PictureFrames& f, const dsp::TrackOptions& opt, dsp::Recording& rec, size_t max_pairs) {
  keep_freed_memory();
  // Chains of consecutive chosen pairs: each frame's pyramid is built once, and every pair
  // detects its features afresh (carry off), as a pair tracked alone would (dsp::track_pair).
  dsp::TrackOptions fresh = opt;
  fresh.carry = false;
  dsp::FeatureTracker tracker(fresh);
  const std::vector<bool> chosen = pairs_to_track(f, rec, max_pairs);
  double scale16 = 0;
  int lost = 0, fb = 0, unlike = 0, pairs = 0;
  const size_t n = f.numbers.size();
  ProgressLine line("rsd: ");
  for (size_t k = 0; k < n; ++k) {
    const bool opens = k + 1 < n && chosen[k + 1];
    if (!chosen[k] && !opens) {
      skip(f, k);
      tracker.restart();
    } else {
      const cv::Mat cur = next_grey(f, k, scale16);
      if (chosen[k] && tracker.holds_frame()) {
        const dsp::PairTracks t = tracker.next(cur);
        for (size_t i = 0; i < t.a.size(); ++i) rec.matches.push_back({f.numbers[k - 1], t.a[i], f.numbers[k], t.b[i]});
        lost += t.lost, fb += t.fb_rejected, unlike += t.ncc_rejected, ++pairs;
        if (!opens) tracker.restart();
      } else {
        tracker.restart();
        tracker.next(cur);  // the first frame of a chain
      }
    }
    line.step("frame", static_cast<long>(k + 1), static_cast<long>(n), std::to_string(rec.matches.size()) + " matches");
  }
  std::printf("rsd: %zu matches over %d consecutive frame pairs (%.0f per pair); dropped %d lost tracks, %d failing the "
              "%.2f px forward-backward check and %d whose patches correlate below %.2f\n",
              rec.matches.size(), pairs, pairs ? double(rec.matches.size()) / pairs : 0.0, lost, fb, opt.max_fb_error_px, unlike,
              opt.min_ncc);
  if (rec.matches.empty()) throw std::runtime_error(f.what + ": no features could be tracked between consecutive frames");
  keep_tracked_frames(f, chosen, rec);
}

void make_landmarks(PictureFrames& f, const dsp::TargetSpec& target, const std::string& target_name, dsp::Recording& rec) {
  if (rec.points.empty()) rec.points = dsp::target_points(target);
  std::set<int> ids;
  for (const dsp::Landmark& p : rec.points) ids.insert(p.id);
  keep_freed_memory();
  double scale16 = 0;
  int seen = 0, unknown = 0;
  const size_t n = f.numbers.size();
  ProgressLine line("rsd: ");
  for (size_t k = 0; k < n; ++k) {
    const cv::Mat img = next_grey(f, k, scale16);
    if (f.usable[k]) {
      const std::vector<dsp::CornerObservation> c = dsp::detect_target(img, target);
      for (const dsp::CornerObservation& ob : c)
        if (ids.count(ob.id)) rec.observations.push_back({f.numbers[k], ob.id, ob.px});
        else ++unknown;
      seen += !c.empty();
    }
    line.step("frame", static_cast<long>(k + 1), static_cast<long>(n), "target in " + std::to_string(seen) + " frames");
  }
  std::printf("rsd: target %s in %d of %zu frames, %zu corner observations of %zu points\n", target_name.c_str(), seen, n,
              rec.observations.size(), rec.points.size());
  if (unknown) std::printf("rsd: %d detected corners have no point in points.csv and were left out\n", unknown);
  if (rec.observations.empty()) throw std::runtime_error(f.what + ": the target " + target_name + " was not found in any frame");
}

dsp::Recording observations_from_pictures(const formats::ImagesRecording& r, const dsp::TrackOptions& opt, size_t max_pairs) {
  dsp::Recording rec = r.rec;
  drivers::ImagesConfig ic;
  if (r.video.empty()) ic.files = r.files;
  else {
    ic.video = r.video;
    for (const std::string& k : r.files) ic.video_frames.push_back(std::stol(k));
  }
  drivers::ImagesSource src(ic);
  src.open();
  src.start();
  dsp::Image buf(src.format().width, src.format().height, src.format().format);
  PictureFrames f;
  f.what = r.video.empty() ? "the recording's pictures" : r.video;
  f.next = [&]() -> std::optional<dsp::Image> {
    drivers::FrameMeta meta;
    if (src.capture(buf.view(), meta, std::chrono::milliseconds(0)) != drivers::CaptureStatus::Frame) return std::nullopt;
    return buf;
  };
  std::vector<double> t;
  for (const dsp::FrameStamp& s : rec.frames) f.numbers.push_back(s.frame), t.push_back(s.t);
  f.times = t;
  const bool gyro = rec.motion == dsp::MotionKind::Gyro;
  f.usable = covered_by_motion(t, gyro ? rec.gyro.front().t : rec.trajectory.front().t,
                               gyro ? rec.gyro.back().t : rec.trajectory.back().t, rec.nominal);
  // Only the frames observed: the rest lie outside the motion.
  std::vector<dsp::FrameStamp> kept;
  for (size_t k = 0; k < rec.frames.size(); ++k)
    if (f.usable[k]) kept.push_back(rec.frames[k]);
  if (kept.size() < rec.frames.size())
    std::fprintf(stderr, "rsd: %zu of %zu frames lie outside the motion's time span (with 50 ms to spare) and are left out\n",
                 rec.frames.size() - kept.size(), rec.frames.size());
  rec.frames = kept;
  if (rec.kind == dsp::ObservationKind::Matches) make_matches(f, opt, rec, max_pairs);
  else make_landmarks(f, *r.target, "of recording.yaml", rec);
  return rec;
}

}  // namespace rsd::tools
