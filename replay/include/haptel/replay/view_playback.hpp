#pragma once
/// @file `haptel replay FILE.mcap`: a session file's operator's view drawn
/// again by the live view's own renderer, from the file's view channel (the
/// model of every frame the live view drew at its MP4's rate, view_record.hpp)
/// and its video channel (each camera picture, decoded again as the live
/// receiver did). No second renderer: the frames of `--mp4` are the live
/// `--record` MP4's frames, drawn from the same models with the same
/// pictures, at the same rate, through the same encoder.
///
/// A file without a view channel (a run without a view, `haptel record`'s)
/// plays its video alone on the screen.
#include <atomic>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <utility>

#include "haptel/mcap/reader.hpp"
#include "haptel/video/codec.hpp"
#include "haptel/view/view.hpp"
#include "haptel/view/view_record.hpp"

namespace haptel::replay {

/// The view's frames of a session file, in log-time order, each with the
/// camera picture it showed.
class ViewPlayback {
 public:
  /// Finds the view and video channels of `reader`'s file (which must
  /// outlive the playback). Throws cli::InputError naming the file when it
  /// has neither, or a set-up message that does not decode.
  explicit ViewPlayback(const mcap::Reader& reader);
  ~ViewPlayback();

  /// The live view's set-up (defaults when the file has no view channel).
  const view::ViewSetup& setup() const { return setup_; }
  std::string file() const { return reader_.path().string(); }
  /// The file has the live view's frames (else: its video alone).
  bool has_view() const { return view_channel_ != 0; }
  /// The first and the last frame's log time (ns, CLOCK_REALTIME).
  uint64_t start_ns() const { return start_ns_; }
  uint64_t end_ns() const { return end_ns_; }

  /// Calls `on_frame` for each frame with log time in [from_ns, to_ns),
  /// `frame.model.video` the picture it showed. Continuing where the last
  /// call ended reads on; anywhere else (a seek) decodes the video again
  /// from the key frame before `from_ns`.
  void Play(uint64_t from_ns, uint64_t to_ns,
            const std::function<void(const view::ViewFrame& frame, uint64_t log_ns)>& on_frame);

  /// Frames whose picture was not in the file (lost, or before the first
  /// key frame): drawn with the latest picture decoded.
  uint64_t pictures_missing() const { return pictures_missing_; }
  /// Video messages that did not decode.
  uint64_t pictures_undecoded() const { return pictures_undecoded_; }

 private:
  struct Picture {
    int64_t capture_wall_ns = 0;
    video::Frame frame;
  };
  void OnVideo(const mcap::MessageView& message);
  const video::Frame* PictureFor(int64_t capture_wall_ns);
  bool Decoded(int64_t capture_wall_ns) const;
  /// Puts the picture `frame` showed on its screen (marked if it was stale).
  void Show(view::ViewFrame& frame);

  const mcap::Reader& reader_;
  view::ViewSetup setup_;
  uint16_t view_channel_ = 0;
  uint16_t video_channel_ = 0;
  std::vector<std::string> topics_;
  bool jpeg_ = false;
  uint64_t start_ns_ = 0;
  uint64_t end_ns_ = 0;
  uint64_t played_to_ns_ = 0;       ///< where the last Play ended (0: nothing played)
  bool awaiting_key_frame_ = true;  ///< since a seek: the video starts at a key frame
  std::unique_ptr<video::VideoDecoder> decoder_;
  std::deque<Picture> pictures_;  ///< decoded, oldest first, from the last one named
  uint64_t next_picture_id_ = 1;
  video::Frame stale_;        ///< the latest picture shown marked stale
  uint64_t stale_of_id_ = 0;  ///< the picture it marks
  view::ViewFrame frame_;
  /// View frames read, waiting for their picture (with their log time).
  std::deque<std::pair<view::ViewFrame, uint64_t>> pending_;
  uint64_t pictures_missing_ = 0;
  uint64_t pictures_undecoded_ = 0;
};

/// Where a replay is in the record, as the person steers it: played at
/// `speed` from `start_ns`, paused and stepped by frames, sought by
/// seconds. Times are the record's log time (ns); `wall_ns` any monotonic
/// clock. Pure logic: the window's keys drive it (ReplayKeys).
class ReplayClock {
 public:
  ReplayClock(uint64_t start_ns, uint64_t end_ns, double speed, double frame_s);
  /// The record's time now.
  uint64_t Now(int64_t wall_ns) const;
  bool paused() const { return paused_; }
  void TogglePause(int64_t wall_ns);
  /// One frame on (`frames` > 0) or back; pauses.
  void Step(int frames, int64_t wall_ns);
  /// `seconds` on or back, within the record; keeps playing or paused.
  void Seek(double seconds, int64_t wall_ns);
  /// Back to the record's start.
  void Home(int64_t wall_ns);
  /// At the record's end.
  bool ended(int64_t wall_ns) const { return Now(wall_ns) >= end_ns_; }

 private:
  void Anchor(uint64_t at_ns, int64_t wall_ns);
  uint64_t start_ns_;
  uint64_t end_ns_;
  double speed_;
  double frame_s_;
  bool paused_ = false;
  uint64_t anchor_ns_ = 0;  ///< record time at anchor_wall_ns_
  int64_t anchor_wall_ns_ = 0;
};

/// What `haptel replay` does with the file.
struct ReplayOptions {
  double speed = 1.0;
  double from_s = 0.0;  ///< s after the record's first frame
  enum class Show { kWindow, kNone } show = Show::kWindow;
  std::filesystem::path mp4;  ///< render offline into this MP4 (empty: none)
};

/// What a replay went through.
struct ReplayReport {
  uint64_t frames = 0;      ///< view frames read (or drawn)
  uint64_t mp4_frames = 0;  ///< frames written to the MP4
  uint64_t pictures = 0;    ///< camera pictures shown
  uint64_t pictures_missing = 0;
  uint64_t pictures_undecoded = 0;
  double duration_s = 0.0;  ///< of the record's view
  bool has_view = false;
};

/// Renders every frame of `playback` from `from_s` into `mp4` offscreen,
/// as fast as the machine draws: each frame drawn at its recorded view
/// clock and written as many times as the live MP4 wrote it. Throws
/// view::ViewError when the MP4 or the GL context cannot be had.
ReplayReport RenderReplayMp4(ViewPlayback& playback, double from_s,
                             const std::filesystem::path& mp4);

/// Reads every frame (and decodes every picture) without drawing: what
/// `--view none` does, and a check that the file reads whole.
ReplayReport ReadReplay(ViewPlayback& playback, double from_s);

/// Plays the record in a window at `speed` from `from_s`: space pauses,
/// `.` and `,` step a frame on and back, the arrows seek 5 s, Home goes to
/// the start; closing the window (or Escape, or `interrupted`) ends it.
ReplayReport PlayReplayWindow(ViewPlayback& playback, double from_s, double speed,
                              const std::atomic<bool>& interrupted);

}  // namespace haptel::replay
