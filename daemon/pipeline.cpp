#include "daemon/pipeline.hpp"

#include <cstdio>
#include <exception>
#include <string>

#include <spdlog/spdlog.h>

#include "drivers/monotonic_clock.hpp"

namespace rsd::daemon {

using drivers::monotonic_ns;

namespace {
std::optional<uint32_t> push_dropping_oldest(DropOldestQueue& q, uint32_t slot, std::atomic<uint64_t>& drops);
}

Pipeline::Pipeline(PipelineConfig cfg, drivers::CameraSource& source, FrameRectifier& rectifier,
                   LcmPublisher& publisher, const VelocityBuffer& velocity)
    : cfg_(cfg), source_(source), rectifier_(&rectifier), pub_(publisher), velocity_(velocity),
      to_rectify_(cfg.queue_depth), to_publish_(cfg.queue_depth), raw_free_(cfg.raw_slots), raw_free_late_(cfg.raw_slots), out_free_(cfg.out_slots) {
  // Each stage holds one slot while working on it; the queues hold the rest.
  if (cfg_.raw_slots < cfg_.queue_depth + 2 || cfg_.out_slots < cfg_.queue_depth + 2)
    throw std::invalid_argument("pipeline: slots must be at least queue_depth + 2");
}

Pipeline::~Pipeline() { stop(); }

std::string Pipeline::camera_error() const { return camera_lost_.load() ? camera_error_ : std::string(); }

void Pipeline::start() {
  const drivers::FrameFormat f = source_.format();
  raw_.clear();
  out_.clear();
  for (size_t i = 0; i < cfg_.raw_slots; ++i) raw_.push_back({dsp::Image(f.width, f.height, f.format), {}, 0});
  for (size_t i = 0; i < cfg_.out_slots; ++i) out_.push_back({dsp::Image(f.width, f.height, f.format), {}, 0, {}, {}, "configured", -1});
  while (raw_free_.get()) {}
  while (raw_free_late_.get()) {}
  while (out_free_.get()) {}
  for (uint32_t i = 0; i < cfg_.raw_slots; ++i) raw_free_.put(i);
  for (uint32_t i = 0; i < cfg_.out_slots; ++i) out_free_.put(i);
  camera_lost_ = end_of_stream_ = finished_ = false;
  capture_done_ = rectify_done_ = false;
  frame_line_.reset();
  running_ = true;
  const RealtimeConfig& rt = cfg_.realtime;
  capture_ = std::thread([this, &rt] {
    schedule("capture", rt.enabled ? rt.capture_priority : 0, rt.capture_cpu);
    capture_loop();
  });
  rectify_ = std::thread([this, &rt] {
    schedule("rectify", 0, rt.rectify_cpu);
    rectify_loop();
  });
  publish_ = std::thread([this, &rt] {
    schedule("publish", 0, rt.publish_cpu);
    publish_loop();
  });
}

// A thread's scheduling, once at its start (never on the hot path); what was not permitted is
// said once per process, and the thread runs on as it was.
void Pipeline::schedule(const char* thread, int priority, int cpu) {
  static std::atomic<bool> warned{false};
  const std::string why = make_thread_realtime(thread, priority, cpu);
  if (!why.empty() && !warned.exchange(true)) spdlog::warn("{}", why);
}

void Pipeline::stop() {
  if (!running_.exchange(false)) return;
  // Downstream stages drain what is queued once upstream has finished: nothing in flight is lost.
  if (capture_.joinable()) capture_.join();
  if (rectify_.joinable()) rectify_.join();
  if (publish_.joinable()) publish_.join();
}

// A free raw slot, or, if the rectifier holds everything up, the oldest queued frame's slot
// (that frame is dropped): the camera never waits.
uint32_t Pipeline::raw_slot_for_capture() {
  for (;;) {
    if (auto s = raw_free_.get()) return *s;
    if (auto s = raw_free_late_.get()) return *s;
    if (cfg_.lossless) {  // wait for the rectifier to return one
      std::this_thread::sleep_for(std::chrono::microseconds(50));
      continue;
    }
    if (auto s = to_rectify_.reclaim_oldest()) {
      stats_.drops.fetch_add(1, std::memory_order_relaxed);
      return *s;
    }
    std::this_thread::yield();  // the rectifier is between popping and returning a slot
  }
}

namespace {

// Queues `slot`; if the queue is full, its oldest frame is dropped and that slot returned
// for reuse (free lists are single-producer: a stage never puts into its own input's list).
std::optional<uint32_t> push_dropping_oldest(DropOldestQueue& q, uint32_t slot, std::atomic<uint64_t>& drops) {
  std::optional<uint32_t> reclaimed;
  while (!q.push(slot)) {
    if (auto old = q.reclaim_oldest()) {
      drops.fetch_add(1, std::memory_order_relaxed);
      reclaimed = old;
    }
  }
  return reclaimed;
}

}  // namespace

// Queues a slot: dropping the oldest queued frame when full, or (lossless) waiting.
std::optional<uint32_t> Pipeline::hand_over(DropOldestQueue& q, uint32_t slot) {
  if (!cfg_.lossless) return push_dropping_oldest(q, slot, stats_.drops);
  while (!q.push(slot)) std::this_thread::sleep_for(std::chrono::microseconds(50));
  return std::nullopt;
}

// Queues a captured frame for the rectifier; the slot to capture the next one into.
uint32_t Pipeline::pass_on(uint32_t slot) {
  const auto reclaimed = hand_over(to_rectify_, slot);
  return reclaimed ? *reclaimed : raw_slot_for_capture();
}

void Pipeline::capture_loop() {
  uint32_t slot = raw_slot_for_capture();
  std::optional<uint32_t> held;  // samples_until_next_frame: the frame waiting for the next one
  while (running_.load(std::memory_order_relaxed)) {
    Raw& r = raw_[slot];
    drivers::CaptureStatus st;
    r.meta.wall_ns = 0;  // a slot's previous frame must not lend its Unix time to this one
    try {
      st = source_.capture(r.image.view(), r.meta, cfg_.capture_timeout);
    } catch (const drivers::CameraError& e) {
      camera_error_ = e.what();
      camera_lost_ = true;
      break;
    } catch (const std::exception& e) {  // any other fault of a source: never the thread's end
      camera_error_ = std::string("capture failed: ") + e.what();
      camera_lost_ = true;  // the service reopens the camera, with backoff, as for a lost one
      break;
    }
    if (st == drivers::CaptureStatus::EndOfStream) {
      end_of_stream_ = true;
      break;
    }
    if (st != drivers::CaptureStatus::Frame) continue;
    const uint64_t samples = velocity_.count();  // all delivered before this frame
    r.ready_ns = monotonic_ns();
    drivers::stamp_wall_clock(r.meta);
    stats_.frames_in.fetch_add(1, std::memory_order_relaxed);
    stats_.last_frame_ns.store(r.ready_ns, std::memory_order_relaxed);
    // A repeated, backward or wild first-row time (a camera's clock fault) would send row times
    // and the velocity looked up for them back, or every later frame: refused, counted, the
    // slot reused; a clock that really restarted is followed from its third frame.
    if (frame_line_.offer(r.meta.first_row_ns) == dsp::TimeLine::Verdict::Held) {
      stats_.refused.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    r.horizon = VelocityBuffer::kAll;
    if (!cfg_.samples_until_next_frame) {
      slot = pass_on(slot);
      continue;
    }
    const std::optional<uint32_t> waiting = std::exchange(held, slot);  // this one waits for the next
    if (waiting) raw_[*waiting].horizon = samples;
    slot = waiting ? pass_on(*waiting) : raw_slot_for_capture();
  }
  if (held) hand_over(to_rectify_, *held);  // the last frame: every sample it could wait for is in
  capture_done_ = true;
  to_rectify_.wake();  // the rectifier may be waiting for a frame that will not come
}

void Pipeline::rectify_loop() {
  std::optional<uint32_t> spare;  // an output slot reclaimed from a dropped frame
  for (;;) {
    const uint32_t seen = to_rectify_.epoch();
    const auto in = to_rectify_.pop();
    if (!in) {
      if (capture_done_.load()) break;
      to_rectify_.wait(seen);  // until the camera delivers (or stops)
      continue;
    }
    std::optional<uint32_t> out_slot = spare ? spare : out_free_.get();
    spare.reset();
    while (!out_slot) {  // the publisher holds every output slot: drop its oldest (or wait)
      if (cfg_.lossless) {
        std::this_thread::sleep_for(std::chrono::microseconds(50));
        out_slot = out_free_.get();
      } else if ((out_slot = to_publish_.reclaim_oldest())) stats_.drops.fetch_add(1, std::memory_order_relaxed);
      else if (!(out_slot = out_free_.get())) std::this_thread::yield();
    }
    Raw& r = raw_[*in];
    Out& o = out_[*out_slot];
    take_up_next_rectifier();
    if (!rectify(r, o)) {  // dropped, counted and said: both slots back
      raw_free_.put(*in);
      spare = out_slot;
      continue;
    }
    (o.result.rectified ? stats_.rectified : stats_.unrectified).fetch_add(1, std::memory_order_relaxed);
    o.raw_slot = cfg_.publish_raw ? static_cast<int>(*in) : -1;
    // The tap sees the raw frame after the frame has gone on (its copy adds nothing to the
    // latency), or before, when the publisher will return the raw slot itself.
    if (tap_ && cfg_.publish_raw) tap_->offer(r.image.view(), r.meta);
    spare = hand_over(to_publish_, *out_slot);
    if (tap_ && !cfg_.publish_raw) tap_->offer(r.image.view(), r.meta);
    if (!cfg_.publish_raw) raw_free_.put(*in);  // else the publisher returns it
    if (spare && out_[*spare].raw_slot >= 0) {  // its raw frame goes back too
      raw_free_.put(static_cast<uint32_t>(out_[*spare].raw_slot));
      out_[*spare].raw_slot = -1;
    }
  }
  rectify_done_ = true;
  to_publish_.wake();
}

bool Pipeline::use_rectifier(FrameRectifier* next) {
  FrameRectifier* expected = nullptr;
  return next_rectifier_.compare_exchange_strong(expected, next);
}

// Between two frames, on the rectify thread: the old rectifier is retired for its owner.
void Pipeline::take_up_next_rectifier() {
  if (FrameRectifier* next = next_rectifier_.load(std::memory_order_acquire)) {
    retired_.store(rectifier_, std::memory_order_release);
    rectifier_ = next;
    next_rectifier_.store(nullptr, std::memory_order_release);
  }
}

void Pipeline::publish_frame(Out& o, uint64_t seq) {
  const dsp::RowTiming& t = o.timing;
  ImageStamp s{o.meta.wall_ns / 1000, o.meta.first_row_ns / 1000, static_cast<int64_t>(seq), t.line_delay_s, t.readout,
               o.meta.exposure_s, o.result.rectified};
  pub_.publish_image(false, o.image.view(), s);
  rsd::frame_info_t& info = pub_.info();
  info.utime = s.frame_utime;  // the per-row times are on the monotonic clock
  info.sequence = static_cast<int64_t>(seq);
  info.source_sequence = static_cast<int64_t>(o.meta.sequence);
  info.line_delay_s = t.line_delay_s;
  info.readout = t.readout == dsp::Readout::TopToBottom ? rsd::frame_info_t::READOUT_TOP_TO_BOTTOM
                                                        : rsd::frame_info_t::READOUT_BOTTOM_TO_TOP;
  info.exposure_s = o.meta.exposure_s;
  info.reference_time_s = o.result.reference_time_s;
  info.rectified = o.result.rectified;
  info.unrectified_reason = o.result.reason;
  for (int i = 0; i < 3; ++i) info.angular_velocity[i] = o.result.w[i], info.linear_velocity[i] = o.result.v[i];
  info.velocity_age_s = o.result.velocity_age_s;
  info.extrapolated = o.result.extrapolated;
  info.extrapolated_s = o.result.extrapolated_s;
  info.imu_wait_s = o.result.imu_wait_s;
  info.max_correction_px = o.result.max_correction_px;
  info.pinhole_sufficient = o.result.pinhole_sufficient;
  info.drops_total = static_cast<int64_t>(stats_.drops.load(std::memory_order_relaxed));
  info.calibration = o.calibration;  // a short literal: no allocation
  pub_.publish_info();
  if (files_ && !output_failed_.load()) {
    try {
      files_->write(o.image.view(), o.meta.sequence);
    } catch (const std::exception& e) {
      output_error_ = e.what();
      output_failed_ = true;
    }
  }
}

// One frame through the rectifier. An exception from it (a frame its maps do not fit: a defect,
// never an input the boundary let through) drops that frame, counted in drops and
// rectify_faults and said the first time and every tenfold: never the rectify thread's end.
bool Pipeline::rectify(Raw& r, Out& o) {
  o.meta = r.meta;
  o.ready_ns = r.ready_ns;
  try {
    o.result = rectifier_->process(r.image.view(), o.image.view(), r.meta, velocity_, r.horizon);
  } catch (const std::exception& e) {
    stats_.drops.fetch_add(1, std::memory_order_relaxed);
    const uint64_t n = stats_.rectify_faults.fetch_add(1, std::memory_order_relaxed) + 1;
    if (rectify_fault_log_.due(n)) spdlog::error("rectifier fault, frame dropped ({} so far): {}", n, e.what());
    return false;
  }
  o.timing = rectifier_->timing();
  o.calibration = rectifier_->calibration();
  return true;
}

void Pipeline::publish_loop() {
  uint64_t seq = 0;
  for (;;) {
    const uint32_t seen = to_publish_.epoch();
    const auto slot = to_publish_.pop();
    if (!slot) {
      if (rectify_done_.load()) break;
      to_publish_.wait(seen);
      continue;
    }
    Out& o = out_[*slot];
    if (o.raw_slot >= 0) {
      Raw& r = raw_[static_cast<size_t>(o.raw_slot)];
      pub_.publish_image(true, r.image.view(), {o.meta.wall_ns / 1000, o.meta.first_row_ns / 1000, static_cast<int64_t>(seq),
                                                o.timing.line_delay_s, o.timing.readout, o.meta.exposure_s, false});
      raw_free_late_.put(static_cast<uint32_t>(o.raw_slot));
      o.raw_slot = -1;
    }
    publish_frame(o, seq++);
    latency_.add(static_cast<double>(monotonic_ns() - o.ready_ns) * 1e-6);
    stats_.frames_out.fetch_add(1, std::memory_order_relaxed);
    out_free_.put(*slot);
  }
  if (end_of_stream_.load()) finished_ = true;
}

}  // namespace rsd::daemon
