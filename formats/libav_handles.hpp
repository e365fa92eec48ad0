// libavformat's handles owned the C++ way, and its error codes as text: what the readers that
// demux with it share (gpmf_mp4, video_frame_times). Only their .cpp files include it.
#pragma once

extern "C" {
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/log.h>
}

#include <memory>
#include <string>

namespace rsd::formats::libav {

struct FormatCloser {
  void operator()(AVFormatContext* c) const { avformat_close_input(&c); }
};
struct PacketFreer {
  void operator()(AVPacket* p) const { av_packet_free(&p); }
};
using Format = std::unique_ptr<AVFormatContext, FormatCloser>;
using Packet = std::unique_ptr<AVPacket, PacketFreer>;

inline std::string error_text(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof text);
  return text;
}

// libavformat's own log lines on stderr ("moov atom not found") say what the readers' errors say
// better, naming the file: off.
inline void quiet() { av_log_set_level(AV_LOG_QUIET); }

inline double seconds(int64_t t, AVRational base) { return static_cast<double>(t) * base.num / base.den; }

}  // namespace rsd::formats::libav
