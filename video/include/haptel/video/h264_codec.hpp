#pragma once
/// @file H.264 for the link's video: libx264 through FFmpeg's libavcodec,
/// tuned for latency, and libavcodec's decoder that says when a frame was
/// lost or corrupt.
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "haptel/video/codec.hpp"

namespace haptel::video {

/// libx264 for a live link: preset veryfast, tune zerolatency (no B-frames,
/// no look-ahead, no frame held back: each Encode returns its frame's
/// bytes), a VBV buffer of about one frame at the target bitrate (a frame
/// never bursts far past its share of the link), and an IDR at least every
/// `key_frame_interval_s` or when asked (RequestKeyFrame). SPS and PPS ride
/// with every IDR, so any IDR starts a decoder. One encode thread: the
/// vehicle's control loops keep the other cores.
///
/// The AVFrame and AVPacket are allocated once and reused; Encode allocates
/// nothing once `out` has grown to a frame's size.
class H264Encoder final : public VideoEncoder {
 public:
  struct Options {
    int width = 640;                    ///< even, > 0
    int height = 480;                   ///< even, > 0
    double rate_hz = 30.0;              ///< frames per second the camera delivers
    int bitrate_kbps = 1000;            ///< target, > 0
    double key_frame_interval_s = 1.0;  ///< the longest stretch between IDRs
  };

  /// Throws std::invalid_argument for a bad size, rate or bitrate and
  /// std::runtime_error when libavcodec has no libx264 or it does not open.
  explicit H264Encoder(const Options& options);
  ~H264Encoder() override;
  H264Encoder(const H264Encoder&) = delete;
  H264Encoder& operator=(const H264Encoder&) = delete;

  CameraCodec codec() const override { return CameraCodec::kH264; }
  /// `bgr` must be CV_8UC3 of the options' size (another size is resized).
  bool Encode(const cv::Mat& bgr, std::vector<uint8_t>& out) override;
  bool last_was_key_frame() const override { return last_key_; }
  void RequestKeyFrame() override { key_frame_requested_ = true; }
  /// The link's estimate, within [kMinFollowKbps, the bitrate it was opened
  /// with]; changed only when it moves by more than 5 % (each change
  /// reconfigures x264).
  void FollowBitrate(double kbps) override;
  static constexpr int kMinFollowKbps = 50;
  /// The target bitrate of the frames encoded from now on (kbit/s, > 0; a
  /// rate controller's knob): x264 is reconfigured at the next frame, VBV
  /// buffer included.
  void SetTargetBitrate(int kbps);
  int target_bitrate_kbps() const { return bitrate_kbps_; }
  uint64_t key_frames() const { return key_frames_; }

 private:
  struct Ffmpeg;
  std::unique_ptr<Ffmpeg> av_;
  Options options_;
  int bitrate_kbps_;
  bool key_frame_requested_ = false;
  bool last_key_ = false;
  uint64_t key_frames_ = 0;
  int64_t pts_ = 0;
  cv::Mat resized_;
  cv::Mat yuv_;
};

/// libavcodec's H.264 decoder, one frame in, one picture out (low delay, one
/// thread: frame threads would hold pictures back). It follows the sender's
/// frame numbers: after a gap, or a frame that does not decode cleanly, it
/// refuses delta frames (their references are gone: decoding them would show
/// smears) until a key frame decodes.
class H264Decoder final : public VideoDecoder {
 public:
  /// Throws std::runtime_error when libavcodec has no H.264 decoder.
  H264Decoder();
  ~H264Decoder() override;
  H264Decoder(const H264Decoder&) = delete;
  H264Decoder& operator=(const H264Decoder&) = delete;

  CameraCodec codec() const override { return CameraCodec::kH264; }
  DecodeResult DecodeFrame(const EncodedFrameView& frame, cv::Mat& image) override;
  bool awaiting_key_frame() const override { return awaiting_key_frame_; }

 private:
  struct Ffmpeg;
  std::unique_ptr<Ffmpeg> av_;
  bool awaiting_key_frame_ = true;  ///< nothing decodes before the first key frame
  bool have_seq_ = false;
  uint64_t last_seq_ = 0;
  cv::Mat yuv_;
};

}  // namespace haptel::video
