#include "formats/video_frame_times.hpp"

#include <algorithm>
#include <stdexcept>

#include "formats/libav_handles.hpp"

namespace rsd::formats {

std::vector<double> read_video_frame_times(const std::string& path) {
  libav::quiet();
  AVFormatContext* raw = nullptr;
  if (const int e = avformat_open_input(&raw, path.c_str(), nullptr, nullptr); e < 0)
    throw std::runtime_error(path + ": cannot open as a video: " + libav::error_text(e));
  const libav::Format ctx(raw);
  if (const int e = avformat_find_stream_info(ctx.get(), nullptr); e < 0)
    throw std::runtime_error(path + ": cannot read its streams: " + libav::error_text(e));
  const int video = av_find_best_stream(ctx.get(), AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
  if (video < 0) throw std::runtime_error(path + ": no video stream");
  const AVRational base = ctx->streams[video]->time_base;
  const int64_t start = ctx->streams[video]->start_time;
  std::vector<double> t;
  const libav::Packet pkt(av_packet_alloc());
  for (int e; (e = av_read_frame(ctx.get(), pkt.get())) != AVERROR_EOF; av_packet_unref(pkt.get())) {
    if (e < 0) throw std::runtime_error(path + ": cannot read: " + libav::error_text(e));
    if (pkt->stream_index != video) continue;
    int64_t pts = pkt->pts != AV_NOPTS_VALUE ? pkt->pts : pkt->dts;
    if (pts == AV_NOPTS_VALUE) throw std::runtime_error(path + ": video frame " + std::to_string(t.size()) + " has no time stamp");
    if (start != AV_NOPTS_VALUE) pts -= start;  // the video's first frame at 0, as a sidecar log counts
    t.push_back(libav::seconds(pts, base));
  }
  std::sort(t.begin(), t.end());  // decode order -> display order
  if (t.empty()) throw std::runtime_error(path + ": its video stream holds no frame");
  return t;
}

}  // namespace rsd::formats
