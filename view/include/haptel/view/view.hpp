#pragma once
/// @file The operator's view: the mediator world drawn in 3-D with SDL2 and
/// OpenGL 3.3 core on a thread of its own, at display rate, into a window or
/// offscreen, optionally recorded to H.264 MP4 (mp4_writer.hpp).
///
/// The view thread owns SDL (video and game controllers) and the GL context.
/// Each frame it asks its ViewSource for the latest ViewModel (the source
/// reads seqlocks and shared pointers: it never blocks the servo loop, the
/// physics thread or the link), draws it, swaps, and hands the SDL events to
/// its EventSink (keyboard, controllers). Closing the window sets
/// InputState::quit through the sink.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>

#include "haptel/core/cli.hpp"
#include "haptel/view/renderer.hpp"
#include "haptel/view/view_model.hpp"

union SDL_Event;
struct SDL_Window;

namespace haptel::view {

/// Set-up errors (no display for a window, no GL 3.3, an MP4 that cannot be
/// opened): one line for the person, e.g. suggesting --record.
class ViewError : public cli::InputError {
 public:
  using cli::InputError::InputError;
};

enum class ViewMode {
  kWindow,     ///< a window on $DISPLAY
  kOffscreen,  ///< no window: rendered for the recorder only (SDL offscreen driver / EGL)
};

/// Takes the frames the view draws at ViewOptions::record_fps — the live
/// MP4's frames, whether an MP4 is written or not — for a session file's
/// view channel (view_record.hpp). Runs on the view thread: it must not
/// block (copy, encode, push into a ring).
class FrameTap {
 public:
  virtual ~FrameTap() = default;
  /// `model` was drawn at `t_s` on the view's clock (what the indicators
  /// flash by) and stands for `copies` consecutive frames at record_fps (a
  /// slow frame is shown, and recorded, for as long as it was on screen;
  /// with an MP4, the copies it took: 0 when its encoder dropped them all).
  virtual void OnFrame(const ViewModel& model, double t_s, int copies) = 0;
};

struct ViewOptions {
  ViewMode mode = ViewMode::kWindow;
  int width = 1024;
  int height = 576;
  double rate_hz = 60.0;         ///< frames per second drawn (vsync off)
  std::filesystem::path record;  ///< MP4 to write (empty: none)
  double record_fps = 30.0;      ///< fixed frame rate of the MP4 (and of the tap)
  FrameTap* tap = nullptr;       ///< the frames at record_fps (null: none); outlives the View
  std::string title = "Haptel";
  ScreenPlacement screen;  ///< where the camera's picture hangs
  StereoOptions stereo;    ///< side by side for a head-mounted display (off: one eye)
  /// SCHED_FIFO priority a window's thread asks for once its GL context is
  /// up (the GL's own threads keep theirs), when the process may; 0: do not
  /// ask. It hands the person's pointer and keys to the mouse device, which
  /// moves the key hand for as long as a key is held: a starved view thread
  /// moved it by its own lateness. Below the physics thread's 70 and the
  /// servo loop's 80.
  int realtime_priority = 60;
};

/// Fills the frame's model on the view thread. Must not block on anything a
/// real-time thread holds.
class ViewSource {
 public:
  virtual ~ViewSource() = default;
  virtual void Fill(ViewModel& model) = 0;
};

/// Receives every SDL event the view thread polls (keyboard, controllers,
/// window). Runs on the view thread.
class EventSink {
 public:
  virtual ~EventSink() = default;
  virtual void OnEvent(const SDL_Event& event) = 0;
  /// `window` is open, `width_px` × `height_px`, before its first event
  /// (SDL says a size only when it changes). Not called offscreen.
  virtual void OnWindowOpened(SDL_Window* window, int width_px, int height_px) {
    (void)window;
    (void)width_px;
    (void)height_px;
  }
  /// The window is about to close (after its last event).
  virtual void OnWindowClosed() {}
};

struct ViewStats {
  uint64_t frames = 0;
  double fps = 0.0;
  double frame_ms_p50 = 0.0;  ///< render + swap time of a frame
  double frame_ms_p99 = 0.0;
  double cpu_share = 0.0;               ///< view thread CPU seconds per wall second
  uint64_t video_frames_shown = 0;      ///< distinct camera frames that reached the screen
  double video_to_screen_ms_p50 = 0.0;  ///< capture stamp -> the swap that first showed it
  double video_to_screen_ms_p99 = 0.0;
  uint64_t recorded_frames = 0;
  uint64_t record_dropped = 0;  ///< frames the encoder could not take in time
  /// "" while the MP4 is whole; else why it is not (a failed write ended
  /// the recording: the file, the OS's reason, the frames it holds).
  std::string record_error;
};

class View {
 public:
  /// Starts the view thread and waits until its window (or offscreen
  /// context) and recorder are up. Throws ViewError when they cannot be.
  /// `sink` may be null; both must outlive the View.
  View(const ViewOptions& options, ViewSource& source, EventSink* sink);
  /// Stops the thread, finishes the MP4.
  ~View();
  View(const View&) = delete;
  View& operator=(const View&) = delete;

  void Stop();
  ViewStats Stats() const;

  /// Whether a window can be opened here ($DISPLAY set and reachable).
  static bool DisplayAvailable();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace haptel::view
