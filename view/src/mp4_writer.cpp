#include "haptel/view/mp4_writer.hpp"

#include <algorithm>
#include <cstring>
#include <mutex>
#include <opencv2/imgproc.hpp>

#include "haptel/view/view.hpp"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/error.h>
#include <libavutil/log.h>
#include <libavutil/opt.h>
}

namespace haptel::view {
namespace {

std::string AvErrorText(int av_error) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(av_error, text, sizeof text);
  return text;
}

}  // namespace

/// The FFmpeg handles, released in the order FFmpeg needs.
struct Mp4Writer::Ffmpeg {
  AVFormatContext* format = nullptr;
  AVCodecContext* codec = nullptr;
  AVStream* stream = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  bool header_written = false;

  ~Ffmpeg() {
    av_packet_free(&packet);
    av_frame_free(&frame);
    avcodec_free_context(&codec);
    if (format != nullptr) {
      if (format->pb != nullptr) avio_closep(&format->pb);
      avformat_free_context(format);
    }
  }
};

Mp4Writer::Mp4Writer(const std::filesystem::path& file, int width, int height, double fps)
    : file_(file), width_(width), height_(height), av_(std::make_unique<Ffmpeg>()) {
  const std::string name = file.string();
  auto refuse = [&](const std::string& why) {
    throw ViewError("view: cannot write " + name + ": " + why + " (H.264 MP4)");
  };
  if (width <= 0 || height <= 0 || width % 2 != 0 || height % 2 != 0) {
    refuse("width and height must be positive and even, got " + std::to_string(width) + "x" +
           std::to_string(height));
  }
  if (!(fps > 0)) refuse("the frame rate must be > 0");
  // Every failure comes back as a return code and is said once, by the
  // recording's owner; FFmpeg's own lines (x264's statistics at the end,
  // its "Error writing" beside ours) stay off stderr.
  static std::once_flag quiet;
  std::call_once(quiet, [] { av_log_set_level(AV_LOG_QUIET); });
  Ffmpeg& av = *av_;
  int ret = avformat_alloc_output_context2(&av.format, nullptr, "mp4", name.c_str());
  if (ret < 0) refuse(AvErrorText(ret));
  const AVCodec* h264 = avcodec_find_encoder_by_name("libx264");
  if (h264 == nullptr) h264 = avcodec_find_encoder(AV_CODEC_ID_H264);
  if (h264 == nullptr) refuse("this FFmpeg has no H.264 encoder");
  av.stream = avformat_new_stream(av.format, nullptr);
  av.codec = avcodec_alloc_context3(h264);
  av.frame = av_frame_alloc();
  av.packet = av_packet_alloc();
  if (av.stream == nullptr || av.codec == nullptr || av.frame == nullptr || av.packet == nullptr) {
    refuse("out of memory");
  }
  const AVRational rate = av_d2q(fps, 100000);
  av.codec->width = width;
  av.codec->height = height;
  av.codec->pix_fmt = AV_PIX_FMT_YUV420P;
  av.codec->time_base = av_inv_q(rate);
  av.codec->framerate = rate;
  // A key frame a second: each is a fragment's start (see the header).
  av.codec->gop_size = std::max(1, static_cast<int>(fps + 0.5));
  if (av.format->oformat->flags & AVFMT_GLOBALHEADER)
    av.codec->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  AVDictionary* codec_options = nullptr;
  // A fast x264 preset: the recording must keep up on a small machine beside
  // the servo loop and the physics.
  if (std::strcmp(h264->name, "libx264") == 0) av_dict_set(&codec_options, "preset", "veryfast", 0);
  ret = avcodec_open2(av.codec, h264, &codec_options);
  av_dict_free(&codec_options);
  if (ret < 0) refuse("the H.264 encoder does not open: " + AvErrorText(ret));
  ret = avcodec_parameters_from_context(av.stream->codecpar, av.codec);
  if (ret < 0) refuse(AvErrorText(ret));
  av.stream->time_base = av.codec->time_base;
  av.stream->avg_frame_rate = rate;
  ret = avio_open(&av.format->pb, name.c_str(), AVIO_FLAG_WRITE);
  if (ret < 0) refuse(AvErrorText(ret));
  AVDictionary* mux_options = nullptr;
  av_dict_set(&mux_options, "movflags", "frag_keyframe+empty_moov+default_base_moof", 0);
  ret = avformat_write_header(av.format, &mux_options);
  av_dict_free(&mux_options);
  if (ret < 0) refuse(AvErrorText(ret));
  av.header_written = true;
  av.frame->format = AV_PIX_FMT_YUV420P;
  av.frame->width = width;
  av.frame->height = height;
  ret = av_frame_get_buffer(av.frame, 0);
  if (ret < 0) refuse(AvErrorText(ret));
}

Mp4Writer::~Mp4Writer() { Close(); }

void Mp4Writer::Fail(const std::string& what, int av_error) {
  if (error_.empty()) {
    error_ = "cannot write " + file_.string() + ": " + what + AvErrorText(av_error) +
             " (the recording ended after " + std::to_string(frames_) + " frames)";
  }
  av_.reset();  // the encoder, its buffers and the file descriptor
}

bool Mp4Writer::Encode(bool flush) {
  Ffmpeg& av = *av_;
  int ret = avcodec_send_frame(av.codec, flush ? nullptr : av.frame);
  if (ret < 0) {
    Fail("the H.264 encoder failed: ", ret);
    return false;
  }
  for (;;) {
    ret = avcodec_receive_packet(av.codec, av.packet);
    if (ret == AVERROR(EAGAIN) || ret == AVERROR_EOF) return true;
    if (ret < 0) {
      Fail("the H.264 encoder failed: ", ret);
      return false;
    }
    av_packet_rescale_ts(av.packet, av.codec->time_base, av.stream->time_base);
    av.packet->stream_index = av.stream->index;
    // The muxer writes through a buffer; a write that failed (ENOSPC,
    // EFBIG, EIO) is returned by this call or the next.
    ret = av_interleaved_write_frame(av.format, av.packet);
    if (ret < 0) {
      Fail("", ret);
      return false;
    }
  }
}

bool Mp4Writer::Write(const cv::Mat& bgr) {
  if (closed_ || failed()) return false;
  CV_Assert(bgr.type() == CV_8UC3 && bgr.cols == width_ && bgr.rows == height_);
  cv::cvtColor(bgr, yuv_, cv::COLOR_BGR2YUV_I420);  // Y, then U, then V, each packed
  Ffmpeg& av = *av_;
  const int ret = av_frame_make_writable(av.frame);  // the encoder may still hold the last one
  if (ret < 0) {
    Fail("out of memory: ", ret);
    return false;
  }
  const uint8_t* planes[3] = {yuv_.data, yuv_.data + width_ * height_,
                              yuv_.data + width_ * height_ + width_ * height_ / 4};
  const int widths[3] = {width_, width_ / 2, width_ / 2};
  const int heights[3] = {height_, height_ / 2, height_ / 2};
  for (int p = 0; p < 3; ++p) {
    for (int row = 0; row < heights[p]; ++row) {
      std::memcpy(av.frame->data[p] + static_cast<ptrdiff_t>(row) * av.frame->linesize[p],
                  planes[p] + static_cast<ptrdiff_t>(row) * widths[p],
                  static_cast<size_t>(widths[p]));
    }
  }
  av.frame->pts = static_cast<int64_t>(frames_);
  if (!Encode(false)) return false;
  ++frames_;
  return true;
}

bool Mp4Writer::Close() {
  if (closed_ || failed()) {
    closed_ = true;
    return !failed();
  }
  closed_ = true;
  if (!Encode(true)) return false;
  Ffmpeg& av = *av_;
  int ret = av_write_trailer(av.format);
  if (ret < 0) {
    Fail("", ret);
    return false;
  }
  // The trailer flushed the buffer and returned its error; the close can
  // still fail (a network file system reports a full disk there).
  ret = avio_closep(&av.format->pb);
  if (ret < 0) {
    Fail("", ret);
    return false;
  }
  av_.reset();
  return true;
}

}  // namespace haptel::view
