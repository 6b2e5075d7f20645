#pragma once
/// @file A picture on its way to the screen: what the video receiver's
/// decoder hands out (VideoReceiver::Latest), what the third-person view
/// renders, and what the view model holds (view::ViewModel::video, its
/// fleet tiles and its inset) — one type, handed on whole, never copied
/// field by field.
#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>

namespace haptel::video {

struct Frame {
  /// BGR 8-bit; null before the first picture. Shared, never copied: whoever
  /// holds it keeps it intact (the receiver makes a new one per picture).
  std::shared_ptr<const cv::Mat> image;
  uint64_t id = 0;              ///< grows with each new picture
  int64_t capture_wall_ns = 0;  ///< the vehicle's CLOCK_REALTIME at capture (0: not a camera's)
  /// An old picture, marked so (MarkStale), shown while the video waits for
  /// a key frame: not a new frame, it takes no part in the video-to-screen
  /// latency.
  bool stale = false;
  /// When it was decoded (CLOCK_REALTIME, as the capture stamp; 0: not
  /// decoded): minus capture_wall_ns, the frame's latency as the view gets it.
  int64_t decoded_wall_ns = 0;
  /// The last command that steered the camera before capture
  /// (VideoFrame.command_seq; 0: none): a command's first picture.
  uint64_t command_seq = 0;
  float zoom = 1.0F;  ///< the camera's zoom at capture
};

/// Whatever hands the screen its latest picture: the video receiver (a
/// vehicle's decoded camera). Any thread, without waiting on the producer
/// for longer than a copy of the handle.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual Frame Latest() const = 0;
};

}  // namespace haptel::video
