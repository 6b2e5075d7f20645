#pragma once
/// @file Video frame codecs: the seam between a camera's frames and the
/// link's bytes. JPEG (OpenCV imgcodecs: every frame decodes alone) and
/// H.264 (FFmpeg's libavcodec with libx264, tuned for latency: see
/// H264Encoder), chosen by `camera.codec` in the vehicle's file.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

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

/// One rung of JpegEncoder's ladder: what a frame is encoded with, and the
/// share of the grabbed frames that are sent.
struct JpegRung {
  int quality = 80;          ///< JPEG quality 1..100
  double scale = 1.0;        ///< of the picture's width and height (0 < scale <= 1)
  double frame_share = 1.0;  ///< of the grabbed frames sent (0 < share <= 1)
  /// Its bitrate as a share of the ladder's top rung's, on the synthetic
  /// camera's pictures (measured; the ladder learns the real ratios as it
  /// goes, this is only its first guess).
  double relative_kbps = 1.0;
};

/// JPEG through OpenCV. Following a bitrate (FollowBitrate), it climbs down
/// a ladder as the issue asks: its quality first, then its resolution, then
/// its frame rate; and back up, a rung at a time, when the rung above is
/// predicted to fit. It judges a rung by the bytes of the frames it encodes
/// there, after kFramesPerRung of them.
///
/// Why the rungs are fine (JpegLadder): the operator's estimate of the link
/// grows to no more than 1.5 times the rate it receives (RateEstimator), so
/// a rung more than about 1.4 times the bytes of the one below can never be
/// climbed back to once left: a cut to half resolution (a third of the
/// bytes) or to every other frame (half) held the video there for good,
/// on a link that could carry twice as much. Adjacent rungs here differ by
/// at most kMaxRungRatio in bitrate: quality in steps of 1 to 2 near 100
/// and of 10 below 80, resolution in steps (7/8, 3/4, 5/8, 9/16, 1/2 of
/// each side), frame rate in fractions (4/5, 2/3, 1/2, 2/5, 1/3, 1/4 of
/// the frames). Going down it jumps to the highest rung predicted to fit.
class JpegEncoder final : public VideoEncoder {
 public:
  static constexpr int kMinQuality = 20;
  static constexpr int kFramesPerRung = 3;
  /// The largest bitrate ratio between adjacent rungs the ladder is built
  /// for (checked on real frames by the tests).
  static constexpr double kMaxRungRatio = 1.35;
  /// The rung above is climbed when predicted at no more than kUpMargin of
  /// the target (kMaxRungRatio / kUpMargin stays under the estimator's 1.5:
  /// every rung can be climbed back to); the rung is left when over
  /// kDownMargin times it.
  static constexpr double kUpMargin = 0.95, kDownMargin = 1.05;

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
  /// The ladder, from its top (the file's quality, full size, every frame)
  /// down; and the rung it stands on (0: the top).
  const std::vector<JpegRung>& ladder() const { return ladder_; }
  size_t rung() const { return rung_; }
  /// Stands on `rung` from now on (a benchmark's or a test's fixed rung;
  /// FollowBitrate moves it again). Throws std::out_of_range past the bottom.
  void SetRung(size_t rung);
  /// Where on the ladder it stands: the scale of the picture sent and the
  /// share of the grabbed frames sent.
  double scale() const { return ladder_[rung_].scale; }
  double frame_share() const { return ladder_[rung_].frame_share; }
  /// The bitrate of the frames sent at this rung (kbit/s), as last measured.
  double rung_kbps() const { return rung_kbps_; }

 private:
  void Climb(size_t bytes);
  /// The bitrate rung `to` is predicted at, from this rung's measured one:
  /// by the ratio last measured between them when there is one, else by the
  /// ladder's first guess.
  double Predicted(size_t to) const;

  int quality_;
  double frame_rate_hz_;
  std::vector<int> params_;
  std::vector<JpegRung> ladder_;
  /// Each rung's bitrate when it was last left (kbit/s; 0: never measured).
  std::vector<double> measured_kbps_;
  size_t rung_ = 0;
  double target_kbps_ = 0.0;   ///< 0: not following
  double frame_credit_ = 0.0;  ///< frames owed at a rung that sends a share of them
  int frames_at_rung_ = 0;
  double rung_kbps_ = 0.0;
  cv::Mat scaled_;
};

/// The rungs of a JpegEncoder whose top quality is `top_quality` (1..100):
/// quality down to JpegEncoder::kMinQuality (or the top's, when lower), then
/// resolution, then frame rate, each adjacent pair at most
/// JpegEncoder::kMaxRungRatio apart in bitrate on the synthetic camera.
std::vector<JpegRung> JpegLadder(int top_quality);

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
/// Width and height from a PNG's header (its IHDR chunk, which must come
/// first), read without decoding. False when `data` is not a PNG with one.
bool PngFrameSize(const uint8_t* data, size_t size, int& width, int& height);

/// Whether a frame a camera delivered as JPEG (a ROS 2 robot's
/// CompressedImage) can go on the link as it is, neither decoded nor
/// encoded again: the vehicle sends JPEG, the frame has the configured size,
/// and sent at the configured frame rate it fits the bitrate the operator
/// last asked for (`target_kbps`; 0, none asked yet: it fits). Otherwise
/// the frame is decoded and goes through the encoder's ladder like any other.
bool JpegPassesThrough(const uint8_t* data, size_t size, const CameraConfig& camera,
                       uint32_t target_kbps);

/// Decodes a camera's JPEG into `bgr_out` at `camera`'s size (resized when
/// it differs), using `scratch` for the decoded picture. False, with
/// `bgr_out` unchanged, when the bytes do not decode.
bool DecodeCameraJpeg(const std::vector<uint8_t>& jpeg, const CameraConfig& camera,
                      cv::Mat& scratch, cv::Mat& bgr_out);

/// The encoder `camera` asks for (codec, quality or bitrate, size, rate).
/// Throws std::runtime_error when the codec cannot be opened (an FFmpeg
/// without libx264), naming the codec.
std::unique_ptr<VideoEncoder> MakeVideoEncoder(const CameraConfig& camera);
/// The decoder for frames of `codec`.
std::unique_ptr<VideoDecoder> MakeVideoDecoder(CameraCodec codec);

}  // namespace haptel::video
