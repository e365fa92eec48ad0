// The hot path: capture -> stamp -> rectify -> publish, on three threads.
//
// Frame slots are allocated once at start (raw slots for the camera, output slots for the
// rectified images) and travel between the threads as indices through lock-free queues that
// drop the oldest frame when a consumer falls behind (counted), so the camera never waits.
// Nothing is allocated per frame.
#pragma once

#include <atomic>
#include <memory>
#include <thread>
#include <vector>

#include "daemon/drop_oldest_queue.hpp"
#include "daemon/frame_files.hpp"
#include "daemon/frame_rectifier.hpp"
#include "daemon/lcm_publisher.hpp"
#include "daemon/latency_stats.hpp"
#include "daemon/realtime.hpp"
#include "daemon/velocity_buffer.hpp"
#include "drivers/camera_source.hpp"
#include "drivers/tenfold_log.hpp"

namespace rsd::daemon {

// Background work that looks at the raw frames (the online calibration's estimator): offered
// each frame on the rectify thread once the frame has been handed on for publishing. It must
// neither wait nor allocate: it copies into a buffer of its own or lets the frame go.
class FrameTap {
 public:
  virtual ~FrameTap() = default;
  virtual void offer(const dsp::ImageView& raw, const drivers::FrameMeta& meta) = 0;
};

struct PipelineConfig {
  size_t raw_slots = 6;
  size_t out_slots = 4;
  size_t queue_depth = 2;
  bool publish_raw = false;
  // Hand frames over without dropping: a stage waits for the next one instead (replaying a
  // log as fast as possible, where every frame must come out for the outputs to be
  // reproducible). A live camera keeps the default: it must never wait.
  bool lossless = false;
  // A replay: each frame waits in the capture thread for the next one and is rectified with
  // the velocity samples delivered before that (the samples covering its last rows, which a live
  // IMU sends after the frame), none later. The source reads on while frames wait for the
  // rectifier: what a frame sees must depend on the log alone, not on how far the reader got.
  // A live camera hands each frame on at once, and its rectifier uses every sample there is.
  bool samples_until_next_frame = false;
  std::chrono::milliseconds capture_timeout{200};
  RealtimeConfig realtime;  // the threads' scheduling and CPUs (daemon/realtime.hpp)
};

struct PipelineStats {
  // frames_in = frames_out + drops + refused + the frames in flight.
  std::atomic<uint64_t> frames_in{0}, frames_out{0}, drops{0}, rectified{0}, unrectified{0};
  std::atomic<uint64_t> refused{0};  // a first-row time off the time line (drivers::frame_time_line)
  std::atomic<uint64_t> rectify_faults{0};  // frames the rectifier threw on (counted in drops too)
  std::atomic<int64_t> last_frame_ns{0};  // CLOCK_MONOTONIC when the newest frame arrived (0: none yet)
};

class Pipeline {
 public:
  Pipeline(PipelineConfig cfg, drivers::CameraSource& source, FrameRectifier& rectifier, LcmPublisher& publisher,
           const VelocityBuffer& velocity);
  ~Pipeline();
  void start();  // allocates the slots, starts the threads
  void stop();   // flushes what is in flight, joins
  const PipelineStats& stats() const { return stats_; }
  LatencyStats& latency() { return latency_; }
  size_t queue_depth() const { return to_rectify_.size() + to_publish_.size(); }
  // Camera loss seen by the capture thread (the service reconnects); cleared by start().
  bool camera_lost() const { return camera_lost_.load(); }
  std::string camera_error() const;
  // The source reported the end of its stream and every frame has been published.
  bool finished() const { return finished_.load(); }
  // Rectified frames also to files (rsd --output-dir/--output-video), written by the publishing
  // thread; set before start(). A write that fails stops the output: output_error() says why.
  void set_frame_files(FrameFiles* files) { files_ = files; }
  // Raw frames also to background work (the online calibration); set before start().
  void set_frame_tap(FrameTap* tap) { tap_ = tap; }
  // A new rectifier (a calibration applied on SIGHUP): the rectify thread takes it up at the
  // start of its next frame, so no frame is dropped or mixes two calibrations. Any thread; one
  // at a time (false while an earlier one has not been taken up). The caller owns both and
  // frees the old one once retired() returns it.
  bool use_rectifier(FrameRectifier* next);
  // The rectifier the rectify thread stopped using (once), or nullptr.
  FrameRectifier* retired() { return retired_.exchange(nullptr); }
  bool output_failed() const { return output_failed_.load(); }
  std::string output_error() const { return output_failed_.load() ? output_error_ : std::string(); }

 private:
  struct Raw {
    dsp::Image image;
    drivers::FrameMeta meta;
    int64_t ready_ns = 0;  // when the last row had been read (latency reference)
    uint64_t horizon = VelocityBuffer::kAll;  // the samples it may use (samples_until_next_frame)
  };
  struct Out {
    dsp::Image image;
    drivers::FrameMeta meta;
    int64_t ready_ns = 0;
    RectifyResult result;
    dsp::RowTiming timing;  // the row timing the frame was rectified with (published with it)
    const char* calibration = "configured";  // and the calibration (FrameRectifier::calibration)
    int raw_slot = -1;  // with publish_raw: the raw frame travelling with this one
  };
  void capture_loop();
  static void schedule(const char* thread, int priority, int cpu);
  void rectify_loop();
  void publish_loop();
  uint32_t raw_slot_for_capture();
  std::optional<uint32_t> hand_over(DropOldestQueue& q, uint32_t slot);
  uint32_t pass_on(uint32_t slot);
  void publish_frame(Out& o, uint64_t seq);
  void take_up_next_rectifier();
  bool rectify(Raw& r, Out& o);

  PipelineConfig cfg_;
  drivers::CameraSource& source_;
  FrameRectifier* rectifier_;  // the rectify thread's own (swapped by it alone)
  std::atomic<FrameRectifier*> next_rectifier_{nullptr}, retired_{nullptr};
  LcmPublisher& pub_;
  const VelocityBuffer& velocity_;
  std::vector<Raw> raw_;
  std::vector<Out> out_;
  DropOldestQueue to_rectify_, to_publish_;
  // Free raw slots come back from the rectifier, or (with publish_raw) from the publisher:
  // one single-producer list each.
  FreeList raw_free_, raw_free_late_, out_free_;
  PipelineStats stats_;
  LatencyStats latency_;
  std::atomic<bool> running_{false}, capture_done_{false}, rectify_done_{false};
  std::atomic<bool> camera_lost_{false}, end_of_stream_{false}, finished_{false};
  std::string camera_error_;  // written by the capture thread before camera_lost_ is set
  dsp::TimeLine frame_line_ = drivers::frame_time_line();  // capture thread; reset by start() (a reopened camera's clock may restart)
  drivers::TenfoldLog rectify_fault_log_;  // the rectify thread's
  FrameFiles* files_ = nullptr;
  FrameTap* tap_ = nullptr;
  std::atomic<bool> output_failed_{false};
  std::string output_error_;  // written by the publishing thread before output_failed_ is set
  std::thread capture_, rectify_, publish_;
};

}  // namespace rsd::daemon
