#include "haptel/video/h264_codec.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavutil/error.h>
#include <libavutil/log.h>
#include <libavutil/opt.h>
}

namespace haptel::video {
namespace {

std::string AvErrorText(int av_error) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(av_error, text, sizeof text);
  return text;
}

/// FFmpeg's own lines (x264's statistics, the decoder's concealment notes)
/// stay off stderr: every failure comes back as a result and is counted.
void QuietFfmpeg() {
  static std::once_flag quiet;
  std::call_once(quiet, [] { av_log_set_level(AV_LOG_QUIET); });
}

/// Copies the packed I420 planes of `yuv` (Y, then U, then V) into `frame`'s
/// planes, which have their own line sizes.
void CopyI420ToFrame(const cv::Mat& yuv, int width, int height, AVFrame* frame) {
  const uint8_t* planes[3] = {yuv.data, yuv.data + width * height,
                              yuv.data + width * height + width * height / 4};
  const int widths[3] = {width, width / 2, width / 2};
  const int heights[3] = {height, height / 2, height / 2};
  for (int p = 0; p < 3; ++p) {
    for (int row = 0; row < heights[p]; ++row) {
      std::memcpy(frame->data[p] + static_cast<ptrdiff_t>(row) * frame->linesize[p],
                  planes[p] + static_cast<ptrdiff_t>(row) * widths[p],
                  static_cast<size_t>(widths[p]));
    }
  }
}

/// The reverse: `frame`'s planes packed into `yuv` (CV_8UC1, height * 3/2 rows).
void CopyFrameToI420(const AVFrame* frame, cv::Mat& yuv) {
  const int width = frame->width;
  const int height = frame->height;
  yuv.create(height * 3 / 2, width, CV_8UC1);
  uint8_t* planes[3] = {yuv.data, yuv.data + width * height,
                        yuv.data + width * height + width * height / 4};
  const int widths[3] = {width, width / 2, width / 2};
  const int heights[3] = {height, height / 2, height / 2};
  for (int p = 0; p < 3; ++p) {
    for (int row = 0; row < heights[p]; ++row) {
      std::memcpy(planes[p] + static_cast<ptrdiff_t>(row) * widths[p],
                  frame->data[p] + static_cast<ptrdiff_t>(row) * frame->linesize[p],
                  static_cast<size_t>(widths[p]));
    }
  }
}

}  // namespace

// ---- Encoder

struct H264Encoder::Ffmpeg {
  AVCodecContext* codec = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;

  ~Ffmpeg() {
    av_packet_free(&packet);
    av_frame_free(&frame);
    avcodec_free_context(&codec);
  }
};

namespace {

/// x264's rate control for `kbps` at `rate_hz`: the average, the same as the
/// ceiling, and a VBV buffer of one frame's share, so that no frame (an IDR
/// included) bursts much past what the link carries in a frame period.
void SetRate(AVCodecContext* codec, int kbps, double rate_hz) {
  const int64_t bits_per_s = static_cast<int64_t>(kbps) * 1000;
  codec->bit_rate = bits_per_s;
  codec->rc_max_rate = bits_per_s;
  codec->rc_buffer_size =
      static_cast<int>(std::max<double>(1000.0, static_cast<double>(bits_per_s) / rate_hz));
}

}  // namespace

H264Encoder::H264Encoder(const Options& options)
    : av_(std::make_unique<Ffmpeg>()), options_(options), bitrate_kbps_(options.bitrate_kbps) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("H264Encoder: " + what); };
  if (options.width <= 0 || options.height <= 0 || options.width % 2 != 0 ||
      options.height % 2 != 0) {
    bad("width and height must be positive and even, got " + std::to_string(options.width) + "x" +
        std::to_string(options.height));
  }
  if (!(options.rate_hz > 0.0)) bad("the frame rate must be > 0");
  if (options.bitrate_kbps <= 0)
    bad("the bitrate must be > 0 kbit/s, got " + std::to_string(options.bitrate_kbps));
  if (!(options.key_frame_interval_s > 0.0)) bad("the key frame interval must be > 0 s");
  QuietFfmpeg();
  const AVCodec* x264 = avcodec_find_encoder_by_name("libx264");
  if (x264 == nullptr)
    throw std::runtime_error("H.264: this FFmpeg's libavcodec has no libx264 encoder");
  Ffmpeg& av = *av_;
  av.codec = avcodec_alloc_context3(x264);
  av.frame = av_frame_alloc();
  av.packet = av_packet_alloc();
  if (av.codec == nullptr || av.frame == nullptr || av.packet == nullptr) throw std::bad_alloc();
  const AVRational rate = av_d2q(options.rate_hz, 100000);
  av.codec->width = options.width;
  av.codec->height = options.height;
  av.codec->pix_fmt = AV_PIX_FMT_YUV420P;
  av.codec->time_base = av_inv_q(rate);
  av.codec->framerate = rate;
  av.codec->gop_size =
      std::max(1, static_cast<int>(std::lround(options.key_frame_interval_s * options.rate_hz)));
  av.codec->max_b_frames = 0;
  av.codec->thread_count = 1;
  SetRate(av.codec, bitrate_kbps_, options.rate_hz);
  AVDictionary* opts = nullptr;
  av_dict_set(&opts, "preset", "veryfast", 0);
  av_dict_set(&opts, "tune", "zerolatency", 0);  // no B-frames, no look-ahead, no frame delay
  av_dict_set(&opts, "forced-idr", "1",
              0);  // a requested key frame is an IDR, not a recovery point
  const int ret = avcodec_open2(av.codec, x264, &opts);
  av_dict_free(&opts);
  if (ret < 0) throw std::runtime_error("H.264: libx264 does not open: " + AvErrorText(ret));
  av.frame->format = AV_PIX_FMT_YUV420P;
  av.frame->width = options.width;
  av.frame->height = options.height;
  if (av_frame_get_buffer(av.frame, 0) < 0) throw std::bad_alloc();
}

H264Encoder::~H264Encoder() = default;

void H264Encoder::SetTargetBitrate(int kbps) {
  if (kbps <= 0)
    throw std::invalid_argument("H264Encoder: bitrate " + std::to_string(kbps) +
                                " kbit/s, expected > 0");
  bitrate_kbps_ = kbps;
  // libavcodec's libx264 wrapper compares these with x264's parameters
  // before each frame and reconfigures x264 when they changed.
  SetRate(av_->codec, kbps, options_.rate_hz);
}

void H264Encoder::FollowBitrate(double kbps) {
  if (!(kbps > 0)) return;
  const int wanted = std::clamp(static_cast<int>(kbps), kMinFollowKbps, options_.bitrate_kbps);
  if (std::abs(wanted - bitrate_kbps_) <= bitrate_kbps_ / 20) return;
  SetTargetBitrate(wanted);
}

bool H264Encoder::Encode(const cv::Mat& bgr, std::vector<uint8_t>& out) {
  out.clear();
  if (bgr.empty() || bgr.type() != CV_8UC3) return false;
  const cv::Mat* source = &bgr;
  if (bgr.cols != options_.width || bgr.rows != options_.height) {
    cv::resize(bgr, resized_, cv::Size(options_.width, options_.height), 0, 0, cv::INTER_AREA);
    source = &resized_;
  }
  cv::cvtColor(*source, yuv_, cv::COLOR_BGR2YUV_I420);
  Ffmpeg& av = *av_;
  if (av_frame_make_writable(av.frame) < 0) return false;  // x264 copies its input: no copy here
  CopyI420ToFrame(yuv_, options_.width, options_.height, av.frame);
  av.frame->pts = pts_++;
  av.frame->pict_type = key_frame_requested_ ? AV_PICTURE_TYPE_I : AV_PICTURE_TYPE_NONE;
  key_frame_requested_ = false;
  if (avcodec_send_frame(av.codec, av.frame) < 0) return false;
  bool key = false;
  for (;;) {
    const int ret = avcodec_receive_packet(av.codec, av.packet);
    if (ret == AVERROR(EAGAIN) || ret == AVERROR_EOF) break;
    if (ret < 0) {
      out.clear();
      return false;
    }
    out.insert(out.end(), av.packet->data, av.packet->data + av.packet->size);
    key = key || (av.packet->flags & AV_PKT_FLAG_KEY) != 0;
    av_packet_unref(av.packet);
  }
  // zerolatency holds no frame back; an empty answer is a failure.
  if (out.empty()) return false;
  last_key_ = key;
  if (key) ++key_frames_;
  return true;
}

// ---- Decoder

struct H264Decoder::Ffmpeg {
  AVCodecContext* codec = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  std::vector<uint8_t>
      padded;  ///< the frame's bytes and the zeroed tail libavcodec reads past the end

  ~Ffmpeg() {
    av_packet_free(&packet);
    av_frame_free(&frame);
    avcodec_free_context(&codec);
  }
};

H264Decoder::H264Decoder() : av_(std::make_unique<Ffmpeg>()) {
  QuietFfmpeg();
  const AVCodec* h264 = avcodec_find_decoder(AV_CODEC_ID_H264);
  if (h264 == nullptr)
    throw std::runtime_error("H.264: this FFmpeg's libavcodec has no H.264 decoder");
  Ffmpeg& av = *av_;
  av.codec = avcodec_alloc_context3(h264);
  av.frame = av_frame_alloc();
  av.packet = av_packet_alloc();
  if (av.codec == nullptr || av.frame == nullptr || av.packet == nullptr) throw std::bad_alloc();
  av.codec->thread_count = 1;  // frame threads hold pictures back by a frame each
  av.codec->flags |= AV_CODEC_FLAG_LOW_DELAY;
  // A damaged frame fails its decode instead of being concealed and shown.
  av.codec->err_recognition |= AV_EF_EXPLODE;
  const int ret = avcodec_open2(av.codec, h264, nullptr);
  if (ret < 0) throw std::runtime_error("H.264: the decoder does not open: " + AvErrorText(ret));
}

H264Decoder::~H264Decoder() = default;

DecodeResult H264Decoder::DecodeFrame(const EncodedFrameView& frame, cv::Mat& image) {
  if (have_seq_ && frame.seq <= last_seq_)
    return DecodeResult::kCorrupt;  // out of order: the stream moved on
  const bool gap = have_seq_ && frame.seq != last_seq_ + 1;
  have_seq_ = true;
  last_seq_ = frame.seq;
  if (gap && !frame.key_frame) {
    awaiting_key_frame_ = true;
    return DecodeResult::kLost;
  }
  if (awaiting_key_frame_ && !frame.key_frame) return DecodeResult::kAwaitingKeyFrame;
  if (frame.data == nullptr || frame.size == 0 ||
      frame.size > static_cast<size_t>(INT32_MAX) - 64) {
    awaiting_key_frame_ = true;
    return DecodeResult::kCorrupt;
  }
  Ffmpeg& av = *av_;
  av.padded.resize(frame.size + AV_INPUT_BUFFER_PADDING_SIZE);
  std::memcpy(av.padded.data(), frame.data, frame.size);
  std::memset(av.padded.data() + frame.size, 0, AV_INPUT_BUFFER_PADDING_SIZE);
  av.packet->data = av.padded.data();
  av.packet->size = static_cast<int>(frame.size);
  av.packet->flags = frame.key_frame ? AV_PKT_FLAG_KEY : 0;
  int ret = avcodec_send_packet(av.codec, av.packet);
  av.packet->data = nullptr;
  av.packet->size = 0;
  bool got = false;
  bool damaged = ret < 0;
  while (ret >= 0) {
    ret = avcodec_receive_frame(av.codec, av.frame);
    if (ret == AVERROR(EAGAIN) || ret == AVERROR_EOF) break;
    if (ret < 0) {
      damaged = true;
      break;
    }
    damaged = damaged || av.frame->decode_error_flags != 0 ||
              (av.frame->flags & AV_FRAME_FLAG_CORRUPT) != 0;
    if (!damaged) {
      CopyFrameToI420(av.frame, yuv_);
      got = true;
    }
    av_frame_unref(av.frame);
  }
  if (damaged || !got) {
    // Later frames refer to this one: nothing good comes before a key frame.
    awaiting_key_frame_ = true;
    return DecodeResult::kCorrupt;
  }
  cv::cvtColor(yuv_, image, cv::COLOR_YUV2BGR_I420);
  awaiting_key_frame_ = false;
  return DecodeResult::kPicture;
}

}  // namespace haptel::video
