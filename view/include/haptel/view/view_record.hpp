#pragma once
/// @file The operator's view as a session file carries it, so that `haptel
/// replay` draws it again with the same renderer: once, the view's set-up
/// (size, frame rates, where the screen hangs, the track's map); then, at
/// the MP4's frame rate, each frame's model as drawn (the shapes in the
/// device frame, the overlay, the gaze, the ghost, the fleet's tiles) and
/// which camera picture was on the screen (its capture stamp: the picture
/// itself is on the video channel).
///
/// Both are CDR (XCDR1, little endian, with its 4-byte encapsulation
/// header), described by the OMG IDL below (schema encoding `omgidl`), so
/// any MCAP tool decodes them. One function per type visits its fields in
/// the IDL's order for both directions: nothing is written twice.
#include <cstdint>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "haptel/view/renderer.hpp"
#include "haptel/view/view.hpp"
#include "haptel/view/view_model.hpp"

namespace haptel::view {

/// The session file's channels of the view.
inline constexpr const char* kViewSetupTopic = "haptel/view/setup";
inline constexpr const char* kViewFrameTopic = "haptel/view/frame";
inline constexpr const char* kViewSetupSchemaName = "haptel::view::ViewSetup";
inline constexpr const char* kViewFrameSchemaName = "haptel::view::ViewFrame";
/// The OMG IDL of both (one text: each schema's data).
extern const char* const kViewRecordIdl;

/// What the view was opened with, once per run.
struct ViewSetup {
  int width = 1024;
  int height = 576;
  double rate_hz = 60.0;     ///< frames drawn per second live
  double record_fps = 30.0;  ///< the live MP4's (and the view channel's) frame rate
  std::string title;
  ScreenPlacement screen;
  std::shared_ptr<const TrackMap> map;  ///< null: no map
};

/// One frame of the view channel: the model as drawn, and the camera
/// picture on the screen, by its capture stamp (0: none yet).
struct ViewFrame {
  ViewModel model;                    ///< video, tile_video and third_person are not carried
  double view_t_s = 0.0;              ///< the view's clock when drawn (FrameTap::OnFrame's t_s)
  int copies = 1;                     ///< the live MP4's frames it stands for (FrameTap::OnFrame's)
  int64_t video_capture_wall_ns = 0;  ///< the screen's picture (0: none yet)
  uint64_t video_id = 0;              ///< the receiver's picture number (0: none)
  /// The picture was shown marked stale (video::MarkStale: the video waited
  /// for a key frame).
  bool video_stale = false;
};

/// A message that is not what its schema says: too short, or a count past
/// the IDL's bound. Says the channel's type and the byte.
class ViewRecordError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The view channel's tap (ViewOptions::tap): each frame the view hands it
/// encoded (EncodeViewFrame) and passed on to `sink` — the session
/// recorder's, which stamps it and queues it without blocking. On the view
/// thread; no allocation once its buffers have grown.
class ViewFrameEncoder final : public FrameTap {
 public:
  using Sink = std::function<void(const uint8_t* data, size_t size)>;
  explicit ViewFrameEncoder(Sink sink) : sink_(std::move(sink)) {}
  void OnFrame(const ViewModel& model, double t_s, int copies) override;
  uint64_t frames() const { return frames_; }

 private:
  Sink sink_;
  ViewFrame frame_;
  std::vector<uint8_t> bytes_;
  uint64_t frames_ = 0;
};

void EncodeViewSetup(const ViewSetup& setup, std::vector<uint8_t>& out);

/// Starts recording a view as `haptel replay` reads it: `options`' set-up
/// (with `map`, null for none) written once through `write_setup`, then each
/// frame the view draws through `write_frame`, by the encoder returned and set
/// as `options.tap` (it must outlive the view). One home for `haptel run`'s
/// and `haptel station`'s session files.
std::unique_ptr<ViewFrameEncoder> StartViewRecord(ViewOptions& options,
                                                  std::shared_ptr<const TrackMap> map,
                                                  const ViewFrameEncoder::Sink& write_setup,
                                                  ViewFrameEncoder::Sink write_frame);
ViewSetup DecodeViewSetup(const uint8_t* data, size_t size);
/// Reuses `out`'s capacity (no allocation once it has grown).
void EncodeViewFrame(const ViewFrame& frame, std::vector<uint8_t>& out);
/// Into `frame`, reusing its shapes' capacity.
void DecodeViewFrame(const uint8_t* data, size_t size, ViewFrame& frame);

}  // namespace haptel::view
