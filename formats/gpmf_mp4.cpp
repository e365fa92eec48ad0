#include "formats/gpmf_mp4.hpp"

#include <algorithm>
#include <cstdint>
#include <memory>
#include <stdexcept>

#include "formats/gpmf.hpp"
#include "formats/libav_handles.hpp"

namespace rsd::formats {

namespace {

using libav::error_text;
using libav::seconds;

// One metadata sample: its bytes and its span on the MP4's clock.
struct Payload {
  std::vector<std::uint8_t> bytes;
  double t_s = 0, duration_s = 0;
};

int gpmf_stream(const AVFormatContext& ctx) {
  for (unsigned i = 0; i < ctx.nb_streams; ++i) {
    const AVCodecParameters& p = *ctx.streams[i]->codecpar;
    if (p.codec_type == AVMEDIA_TYPE_DATA && p.codec_tag == MKTAG('g', 'p', 'm', 'd')) return static_cast<int>(i);
  }
  return -1;
}

// The payload's samples spread evenly over its span: [t, t + duration).
void add_gyro(const Payload& p, int index, const std::string& path, GpmfVideo& out) {
  const std::string what = path + ": GPMF payload " + std::to_string(index) + " (at " + std::to_string(p.t_s) + " s)";
  const std::vector<GpmfGyro> streams = read_gpmf_gyro(p.bytes.data(), p.bytes.size(), what);
  if (streams.empty()) throw std::runtime_error(what + " has no gyro stream (GYRO)");
  const GpmfGyro& g = streams.front();  // the camera's own: the first device GoPro writes
  if (index == 0) out.orin = g.orin, out.device = g.device;
  else if (g.orin != out.orin)
    throw std::runtime_error(what + ": the gyro's axis order ORIN is '" + g.orin + "', the payloads before it '" + out.orin + "'");
  const double n = static_cast<double>(g.rate_rad_s.size());
  for (std::size_t i = 0; i < g.rate_rad_s.size(); ++i) {
    out.gyro_t_s.push_back(p.t_s + p.duration_s * static_cast<double>(i) / n);
    out.gyro_rad_s.push_back(g.rate_rad_s[i]);
  }
}

}  // namespace

GpmfVideo read_gpmf_video(const std::string& path) {
  libav::quiet();
  AVFormatContext* raw = nullptr;
  // The MP4 demuxer only: libavformat would take other files for something else (a raw GPMF
  // payload for a picture).
  if (const int e = avformat_open_input(&raw, path.c_str(), av_find_input_format("mp4"), nullptr); e < 0)
    throw std::runtime_error(path + ": cannot open as an MP4: " + error_text(e));
  const libav::Format ctx(raw);
  if (const int e = avformat_find_stream_info(ctx.get(), nullptr); e < 0)
    throw std::runtime_error(path + ": cannot read its streams: " + error_text(e));
  const int video = av_find_best_stream(ctx.get(), AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
  if (video < 0) throw std::runtime_error(path + ": no video stream");
  const int meta = gpmf_stream(*ctx);
  if (meta < 0) throw std::runtime_error(path + ": no GPMF metadata track (a GoPro camera's 'gpmd' data stream)");
  const AVStream& vs = *ctx->streams[video];
  const AVStream& ms = *ctx->streams[meta];

  GpmfVideo out;
  out.width = vs.codecpar->width, out.height = vs.codecpar->height;
  // GoPro's udta FIRM atom, which libavformat's MP4 demuxer gives as the tag `firmware`.
  if (const AVDictionaryEntry* f = av_dict_get(ctx->metadata, "firmware", nullptr, 0)) out.firmware = f->value;
  std::vector<Payload> payloads;
  const libav::Packet pkt(av_packet_alloc());
  for (int e; (e = av_read_frame(ctx.get(), pkt.get())) != AVERROR_EOF; av_packet_unref(pkt.get())) {
    if (e < 0) throw std::runtime_error(path + ": cannot read: " + error_text(e));
    const int64_t pts = pkt->pts != AV_NOPTS_VALUE ? pkt->pts : pkt->dts;
    if (pkt->stream_index == video) {
      if (pts == AV_NOPTS_VALUE) throw std::runtime_error(path + ": a video frame without a time stamp");
      out.frame_t_s.push_back(seconds(pts, vs.time_base));
    } else if (pkt->stream_index == meta) {
      if (pts == AV_NOPTS_VALUE) throw std::runtime_error(path + ": a GPMF payload without a time stamp");
      payloads.push_back({std::vector<std::uint8_t>(pkt->data, pkt->data + pkt->size), seconds(pts, ms.time_base),
                          seconds(pkt->duration, ms.time_base)});
    }
  }
  std::sort(out.frame_t_s.begin(), out.frame_t_s.end());  // decode order -> display order
  if (payloads.empty()) throw std::runtime_error(path + ": its GPMF track holds no payload");
  for (std::size_t k = 0; k < payloads.size(); ++k) {
    // A payload without a duration ends where the next begins (the last: as long as the one before).
    Payload& p = payloads[k];
    if (!(p.duration_s > 0)) p.duration_s = k + 1 < payloads.size() ? payloads[k + 1].t_s - p.t_s : k > 0 ? payloads[k - 1].duration_s : 1.0;
    add_gyro(p, static_cast<int>(k), path, out);
  }
  out.payloads = static_cast<int>(payloads.size());
  return out;
}

}  // namespace rsd::formats
