#pragma once
/// @file Where a vehicle's camera frames come from: the synthetic camera, a
/// V4L2 device or a video file, behind one interface (config `camera.source`).
///
/// A source is made and opened at set-up (MakeCameraSource throws a
/// ConfigError naming the config file, the key and the device or file when it
/// cannot be opened), then grabbed from one thread — the vehicle node's camera
/// loop, never its control loop — at `camera.rate_hz`. Every source delivers
/// BGR frames of the configured size.
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>
#include <vector>

#include "haptel/config/track.hpp"
#include "haptel/config/vehicle.hpp"
#include "haptel/video/synthetic_camera.hpp"

namespace haptel::video {

class CameraSource {
 public:
  virtual ~CameraSource() = default;
  /// The next frame into `bgr_out` (CV_8UC3, the configured size; its buffer
  /// is reused when it already fits). `pose` is where the vehicle is: the
  /// synthetic camera renders the view from there, real cameras ignore it.
  /// False when there is no frame: a device that delivered none (try again
  /// next tick), or a file that has ended (see Ended()). `bgr_out` is then
  /// left as it was.
  virtual bool Grab(const CameraPose& pose, cv::Mat& bgr_out) = 0;
  /// True once a file that does not loop has delivered its last frame: Grab
  /// will not succeed again.
  virtual bool Ended() const { return false; }
  /// For messages: "synthetic", "device /dev/video0", "file /path/lap.avi".
  virtual std::string Describe() const = 0;
  /// True when Grab draws the frame from the pose it is given, so the frame
  /// shows the moment Grab starts; false when Grab waits for a frame that
  /// exists only when it returns (a device, a file).
  virtual bool RendersAtGrab() const { return false; }
  /// True for a source whose frames arrive as JPEG (a ROS 2 robot's
  /// CompressedImage): GrabJpeg then gives them undecoded, so that a frame
  /// that already fits the link is sent as it is (JpegPassesThrough).
  virtual bool DeliversJpeg() const { return false; }
  /// The next frame's JPEG bytes into `jpeg_out` (its capacity reused),
  /// undecoded; false as Grab is when there is none. Only for sources
  /// that DeliversJpeg().
  virtual bool GrabJpeg(std::vector<uint8_t>& /*jpeg_out*/) { return false; }
};

/// The synthetic first-person view of a Track (SyntheticCamera).
class SyntheticSource final : public CameraSource {
 public:
  /// Keeps a reference to `track`, which must outlive the source.
  SyntheticSource(const Track& track, const CameraConfig& config) : camera_(track, config) {}
  bool Grab(const CameraPose& pose, cv::Mat& bgr_out) override {
    camera_.Render(pose, bgr_out);
    return true;
  }
  std::string Describe() const override { return "synthetic"; }
  bool RendersAtGrab() const override { return true; }

 private:
  SyntheticCamera camera_;
};

/// A V4L2 device or a video file, through cv::VideoCapture.
///
/// Device: opened with CAP_V4L2 and asked for the configured size and frame
/// rate (what it gives is resized if it differs). File: opened with
/// CAP_FFMPEG (CAP_ANY if FFmpeg cannot), one frame per Grab whatever the
/// file's own frame rate — the caller paces it; with `loop` the first frame
/// follows the last, else Ended() turns true after the last.
class CaptureCamera final : public CameraSource {
 public:
  /// Opens `config.device` (source kDevice) or `config.file` (kFile); throws
  /// ConfigError "<config_file>: key 'camera.device': cannot open /dev/video9
  /// (no such device)" and the like when it cannot, std::invalid_argument for
  /// a synthetic source, and ConfigFieldError (a std::invalid_argument) for a
  /// `config` CameraConfig::ValidateOrThrow refuses.
  CaptureCamera(const CameraConfig& config, const std::string& config_file);

  bool Grab(const CameraPose& pose, cv::Mat& bgr_out) override;
  bool Ended() const override { return ended_; }
  std::string Describe() const override;

  /// Size the device or file delivers (before resizing), as read after opening.
  cv::Size native_size() const { return native_size_; }
  /// Times a file started again at its first frame.
  uint64_t loops() const { return loops_; }

 private:
  bool ReadFrame();
  bool Rewind();
  bool OpenFile();
  bool Read();

  CameraConfig config_;
  std::string config_file_;
  std::string target_;  ///< the device path or the file path, for messages
  cv::VideoCapture capture_;
  cv::Mat raw_;
  cv::Size native_size_;
  uint64_t loops_ = 0;
  bool ended_ = false;
  bool pending_ = false;  ///< raw_ holds a frame read at opening, not yet delivered
};

/// The source `config.source` names. `track` is the world a synthetic camera
/// renders (required for kSynthetic, unused otherwise); `config_file` names
/// the vehicle config file in error messages. Throws ConfigError when a
/// device or file cannot be opened, std::invalid_argument for a synthetic
/// source without a track or with an impossible camera.
std::unique_ptr<CameraSource> MakeCameraSource(const CameraConfig& config, const Track* track,
                                               const std::string& config_file);

/// Watches a source's Grab results on the camera loop, so that a device that
/// stops delivering is reported once, not once per tick: Stalled() fires the
/// first time at least `min_failures` grabs in a row have failed over at
/// least `min_duration_s` since the last good frame (or since the first
/// failure), and not again for this source. Plain counters; no clock of its
/// own (the caller passes the tick's time).
class GrabMonitor {
 public:
  enum class Event {
    kNone,
    kStalled,  ///< first stall: report it
  };
  explicit GrabMonitor(int min_failures = 3, double min_duration_s = 1.0)
      : min_failures_(min_failures), min_duration_ns_(static_cast<int64_t>(min_duration_s * 1e9)) {}

  Event OnGrab(bool ok, int64_t now_ns);

  uint64_t failures() const { return failures_; }  ///< failed grabs, in all
  uint64_t stalls() const { return stalls_; }      ///< stretches of failures long enough to count
  int failures_in_a_row() const { return in_a_row_; }
  /// Whether the current stretch of failures counts as a stall.
  bool stalled() const { return stalled_now_; }

 private:
  int min_failures_;
  int64_t min_duration_ns_;
  int64_t first_failure_ns_ = 0;
  int in_a_row_ = 0;
  uint64_t failures_ = 0;
  uint64_t stalls_ = 0;
  bool stalled_now_ = false;
  bool reported_ = false;
};

}  // namespace haptel::video
