#pragma once
/// @file Video frame codecs: the seam between a camera's frames and the
/// link's bytes. JPEG (OpenCV imgcodecs: every frame decodes alone) and
/// H.264 (FFmpeg's libavcodec with libx264, tuned for latency: see
/// H264Encoder), chosen by `camera.codec` in the vehicle's file.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "haptel/config/vehicle.hpp"

namespace haptel::video {

/// Turns BGR frames into a codec's bytes, one frame in, one frame out (no
/// frame is held back: no B-frames, no look-ahead).
class VideoEncoder {
 public:
  virtual ~VideoEncoder() = default;
  virtual CameraCodec codec() const = 0;
  /// Encodes a BGR image into `out` (replacing its contents, reusing its
  /// capacity). Returns false (and leaves `out` empty) when it cannot.
  virtual bool Encode(const cv::Mat& bgr, std::vector<uint8_t>& out) = 0;
  /// Whether the frame last encoded decodes alone (JPEG: always; H.264: an IDR).
  virtual bool last_was_key_frame() const = 0;
  /// Makes the next frame a key frame (an operator lost a frame and waits
  /// for one). JPEG's frames all are.
  virtual void RequestKeyFrame() {}
  /// Follows the link: aims at `kbps` (the operator's estimate of what the
  /// link carries, RateEstimator), never above the bitrate or quality the
  /// vehicle's file gives. H.264: its bitrate; JPEG: its ladder.
  virtual void FollowBitrate(double /*kbps*/) {}
  /// Whether the frame grabbed now is to be skipped (JPEG's last rung: a
  /// lower frame rate). Called once per grabbed frame, before Encode.
  virtual bool SkipFrame() { return false; }
};

/// What became of one encoded frame handed to a VideoDecoder.
enum class DecodeResult {
  kPicture,           ///< decoded: `image` holds the new picture
  kCorrupt,           ///< the bytes did not decode (or decoded with errors)
  kLost,              ///< frames before this one never came: its references are gone
  kAwaitingKeyFrame,  ///< a frame that needs lost references, refused until a key frame
};

/// One encoded frame as it came off the link.
struct EncodedFrameView {
  const uint8_t* data = nullptr;
  size_t size = 0;
  uint64_t seq = 0;        ///< the sender's frame number: one more per frame sent
  bool key_frame = false;  ///< decodes alone (the sample says so)
};

/// Turns a codec's bytes back into BGR pictures and says when a frame was
/// lost or corrupt, so that the receiver can ask for a key frame.
class VideoDecoder {
 public:
  virtual ~VideoDecoder() = default;
  virtual CameraCodec codec() const = 0;
  /// Decodes `frame` into `image` (BGR); `image` is left unchanged unless
  /// the result is kPicture.
  virtual DecodeResult DecodeFrame(const EncodedFrameView& frame, cv::Mat& image) = 0;
  /// True while no picture can come before a key frame does (after a loss or
  /// a corrupt frame of a codec whose frames depend on earlier ones).
  virtual bool awaiting_key_frame() const { return false; }
};

/// JPEG through OpenCV. Following a bitrate (FollowBitrate), it climbs down
/// a ladder as the issue asks: its quality first (in steps of 10, down to
/// kMinQuality), then its resolution (half each way), then its frame rate
/// (one frame in 2, 3, 4 kept); and back up, a rung at a time, when the
/// rung above is predicted to fit. It judges a rung by the bytes of the
/// frames it encodes there, after kFramesPerRung of them.
class JpegEncoder final : public VideoEncoder {
 public:
  static constexpr int kMinQuality = 20;
  static constexpr int kMaxSkip = 3;  ///< at most 3 frames in 4 skipped
  static constexpr int kFramesPerRung = 3;

  /// @param quality JPEG quality 1..100 (the ladder's top); throws
  /// std::invalid_argument otherwise. `frame_rate_hz`: the camera's, for the
  /// ladder's bitrate.
  explicit JpegEncoder(int quality, double frame_rate_hz = 30.0);
  CameraCodec codec() const override { return CameraCodec::kJpeg; }
  /// Encodes a BGR image into `out` (replacing its contents, reusing capacity).
  /// Returns false (and leaves `out` empty) when OpenCV cannot encode it.
  bool Encode(const cv::Mat& bgr, std::vector<uint8_t>& out) override;
  bool last_was_key_frame() const override { return true; }
  /// The quality of the frames encoded from now on (a rate controller's
  /// knob); throws std::invalid_argument outside 1..100.
  void SetQuality(int quality);
  int quality() const { return quality_; }

  void FollowBitrate(double kbps) override { target_kbps_ = kbps; }
  bool SkipFrame() override;
  /// Where on the ladder it stands: the scale of the picture sent (1 or
  /// 0.5) and the frames skipped of each skip() + 1.
  double scale() const { return scale_; }
  int skip() const { return skip_; }
  /// The bitrate of the frames sent at this rung (kbit/s), as last measured.
  double rung_kbps() const { return rung_kbps_; }

 private:
  void Climb(size_t bytes);

  int quality_;
  int top_quality_;
  double frame_rate_hz_;
  std::vector<int> params_;
  double target_kbps_ = 0.0;  ///< 0: not following
  double scale_ = 1.0;
  int skip_ = 0;
  int skip_count_ = 0;
  int frames_at_rung_ = 0;
  double rung_kbps_ = 0.0;
  cv::Mat scaled_;
};

class JpegDecoder final : public VideoDecoder {
 public:
  CameraCodec codec() const override { return CameraCodec::kJpeg; }
  /// Decodes JPEG bytes into `image` (BGR). Returns false for empty or corrupt
  /// data, counting it in failures(); `image` is then left unchanged.
  bool Decode(const uint8_t* data, size_t size, cv::Mat& image);
  /// Every JPEG decodes alone: a gap before a frame costs nothing.
  DecodeResult DecodeFrame(const EncodedFrameView& frame, cv::Mat& image) override;
  uint64_t failures() const { return failures_; }

 private:
  uint64_t failures_ = 0;
};

/// Width and height from a JPEG's frame header (its SOFn segment), read
/// without decoding. False when `data` is not a JPEG with one.
bool JpegFrameSize(const uint8_t* data, size_t size, int& width, int& height);

/// Whether a frame a camera delivered as JPEG (a ROS 2 robot's
/// CompressedImage) can go on the link as it is, neither decoded nor
/// encoded again: the vehicle sends JPEG, the frame has the configured size,
/// and sent at the configured frame rate it fits the bitrate the operator
/// last asked for (`target_kbps`; 0, none asked yet: it fits). Otherwise
/// the frame is decoded and goes through the encoder's ladder like any other.
bool JpegPassesThrough(const uint8_t* data, size_t size, const CameraConfig& camera, uint32_t target_kbps);

/// Decodes a camera's JPEG into `bgr_out` at `camera`'s size (resized when
/// it differs), using `scratch` for the decoded picture. False, with
/// `bgr_out` unchanged, when the bytes do not decode.
bool DecodeCameraJpeg(const std::vector<uint8_t>& jpeg, const CameraConfig& camera, cv::Mat& scratch,
                      cv::Mat& bgr_out);

/// The encoder `camera` asks for (codec, quality or bitrate, size, rate).
/// Throws std::runtime_error when the codec cannot be opened (an FFmpeg
/// without libx264), naming the codec.
std::unique_ptr<VideoEncoder> MakeVideoEncoder(const CameraConfig& camera);
/// The decoder for frames of `codec`.
std::unique_ptr<VideoDecoder> MakeVideoDecoder(CameraCodec codec);

}  // namespace haptel::video
