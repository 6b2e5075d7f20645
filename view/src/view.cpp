#include "haptel/view/view.hpp"

#include <SDL2/SDL.h>
#include <pthread.h>
#include <time.h>

#include <atomic>
#include <condition_variable>
#include <cstdlib>
#include <deque>
#include <future>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <thread>

#define GL_GLEXT_PROTOTYPES 1
#include <GL/glcorearb.h>

#include "haptel/core/histogram.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/loop_meter.hpp"
#include "haptel/view/canvas.hpp"
#include "haptel/view/mp4_writer.hpp"
#include "haptel/view/renderer.hpp"

namespace haptel::view {
namespace {

/// Leaves SDL as the view found it: its own subsystems quit, and SDL itself
/// only when nothing else uses it (an sdl-ff device's thread keeps its
/// joystick and haptic subsystems through the view's end).
void QuitViewSdl() {
  SDL_QuitSubSystem(SDL_INIT_VIDEO | SDL_INIT_GAMECONTROLLER);
  if (SDL_WasInit(0) == 0) SDL_Quit();
}

int64_t Now(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

void SleepUntil(int64_t t_ns) {
  timespec ts{};
  ts.tv_sec = t_ns / 1000000000;
  ts.tv_nsec = t_ns % 1000000000;
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

/// The MP4: frames read back on the view thread go through a short queue to
/// an encoder thread (H.264 is far slower than a readback); when the queue is
/// full the frame is dropped and counted rather than stalling the view. A
/// write that fails (a full disk) ends the recording: the encoder thread
/// says so once on stderr, and the view goes on without it.
class Mp4Recorder {
 public:
  Mp4Recorder(const std::filesystem::path& file, int width, int height, double fps)
      : writer_(WithItsFolder(file), width, height, fps) {
    encoder_ = std::thread([this] { Encode(); });
  }
  ~Mp4Recorder() { Finish(); }

  /// View thread: queue `rgba` (GL order) `copies` times (fixed-rate video:
  /// a slow frame is shown for as long as it was on the screen). Returns
  /// how many were queued (the others dropped).
  int Push(const cv::Mat& rgba, int copies) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (ended_) return 0;  // the file failed: nothing more goes to it
    int queued = 0;
    for (int i = 0; i < copies; ++i) {
      if (queue_.size() >= kCapacity) {
        ++dropped_;
        continue;
      }
      queue_.push_back(queued == 0 ? rgba.clone() : queue_.back());
      ++queued;
    }
    wake_.notify_one();
    return queued;
  }
  void Finish() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (done_) return;
      done_ = true;
    }
    wake_.notify_one();
    if (encoder_.joinable()) encoder_.join();
    if (!writer_.Close()) Report();
  }
  uint64_t written() const { return written_.load(); }
  uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  /// "" while the file is whole; once Finish() returned, final.
  std::string error() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return error_;
  }

 private:
  static constexpr size_t kCapacity = 12;

  /// `file`, its folder made if it can be (the writer says if it cannot).
  static const std::filesystem::path& WithItsFolder(const std::filesystem::path& file) {
    if (file.has_parent_path()) {
      std::error_code ec;
      std::filesystem::create_directories(file.parent_path(), ec);
    }
    return file;
  }

  /// Once, from whichever thread saw the failure first.
  void Report() {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!error_.empty()) return;
    error_ = writer_.error();
    log::Error("the operator's view is not recorded whole: " + error_);
  }

  void Encode() {
    cv::Mat flipped;
    cv::Mat bgr;
    for (;;) {
      cv::Mat rgba;
      {
        std::unique_lock<std::mutex> lock(mutex_);
        wake_.wait(lock, [&] { return done_ || !queue_.empty(); });
        if (queue_.empty()) return;  // done and drained
        rgba = queue_.front();
        queue_.pop_front();
      }
      cv::flip(rgba, flipped, 0);
      cv::cvtColor(flipped, bgr, cv::COLOR_RGBA2BGR);
      if (!writer_.Write(bgr)) {
        Report();
        std::lock_guard<std::mutex> lock(mutex_);
        ended_ = true;
        queue_.clear();
        return;
      }
      written_.fetch_add(1);
    }
  }

  Mp4Writer writer_;  // used by the encoder thread only, then by Finish() after the join
  std::thread encoder_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<cv::Mat> queue_;
  bool done_ = false;
  bool ended_ = false;  ///< the file failed: the recording is over
  uint64_t dropped_ = 0;
  std::string error_;
  std::atomic<uint64_t> written_{0};
};

}  // namespace

Canvas::Canvas(const ViewOptions& options) {
  bool sdl_up = false;
  try {
    if (options.mode == ViewMode::kOffscreen && std::getenv("SDL_VIDEODRIVER") == nullptr) {
      SDL_SetHint(SDL_HINT_VIDEODRIVER, "offscreen");
    }
    if (options.mode == ViewMode::kWindow && !View::DisplayAvailable()) {
      throw ViewError(
          "no display for a window ($DISPLAY is not set or not reachable); use --record FILE.mp4 "
          "to "
          "render offscreen, or --view none");
    }
    SDL_SetHint(SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS, "1");
    SDL_SetHint(SDL_HINT_NO_SIGNAL_HANDLERS, "1");  // Ctrl-C stays the session's
    // A click that gives the window the focus grasps too: the mouse
    // device's hand is held from that press (SDL drops a press within
    // 10 ms of its focus event by default, and a loaded view thread reads
    // both at once: the hand then followed the pointer and was never held).
    SDL_SetHint(SDL_HINT_MOUSE_FOCUS_CLICKTHROUGH, "1");
    if (SDL_Init(SDL_INIT_VIDEO | SDL_INIT_GAMECONTROLLER) != 0) {
      throw ViewError(std::string("view: SDL cannot start its video: ") + SDL_GetError());
    }
    sdl_up = true;
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_CORE);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, 3);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, 3);
    SDL_GL_SetAttribute(SDL_GL_DOUBLEBUFFER, 1);
    SDL_GL_SetAttribute(SDL_GL_DEPTH_SIZE, 24);
    const Uint32 flags =
        SDL_WINDOW_OPENGL | (options.mode == ViewMode::kOffscreen ? SDL_WINDOW_HIDDEN : 0);
    window_ = SDL_CreateWindow(options.title.c_str(), SDL_WINDOWPOS_CENTERED,
                               SDL_WINDOWPOS_CENTERED, options.width, options.height, flags);
    if (window_ == nullptr)
      throw ViewError(std::string("view: cannot open a window: ") + SDL_GetError());
    context_ = SDL_GL_CreateContext(window_);
    if (context_ == nullptr) {
      throw ViewError(std::string("view: no OpenGL 3.3 core context: ") + SDL_GetError());
    }
    SDL_GL_SetSwapInterval(0);  // paced by the caller, not the display
    renderer_ =
        std::make_unique<Renderer>(options.width, options.height, options.screen, options.stereo);
  } catch (...) {
    renderer_.reset();
    if (context_ != nullptr) SDL_GL_DeleteContext(context_);
    if (window_ != nullptr) SDL_DestroyWindow(window_);
    if (sdl_up) QuitViewSdl();
    throw;
  }
}

Canvas::~Canvas() {
  renderer_.reset();
  SDL_GL_DeleteContext(context_);
  SDL_DestroyWindow(window_);
  QuitViewSdl();
}

void Canvas::Swap() {
  SDL_GL_SwapWindow(window_);
  glFinish();  // the frame is on the screen (or in the offscreen buffer) now
}

bool View::DisplayAvailable() {
  const char* display = std::getenv("DISPLAY");
  if (display == nullptr || display[0] == '\0') return false;
  // The X socket of a local display must exist (":N" or ":N.S").
  if (display[0] == ':') {
    const std::string number(display + 1, std::strcspn(display + 1, "."));
    return std::filesystem::exists("/tmp/.X11-unix/X" + number);
  }
  return true;  // a remote display: SDL will say if it cannot reach it
}

struct View::Impl {
  ViewOptions options;
  ViewSource& source;
  EventSink* sink;
  std::thread thread;
  std::atomic<bool> stop{false};

  // Measured on the view thread, read by Stats().
  Histogram frame_us{100.0, 2000};            // 0.1 ms bins up to 200 ms
  Histogram video_to_screen_us{500.0, 1000};  // 0.5 ms bins up to 500 ms
  std::atomic<uint64_t> frames{0};
  std::atomic<uint64_t> video_frames_shown{0};
  std::atomic<double> fps{0.0};  // mean over the run
  std::atomic<double> cpu_share{0.0};
  std::unique_ptr<Mp4Recorder> recorder;
  bool realtime = false;  ///< the view thread's, while it has SCHED_FIFO

  Impl(const ViewOptions& o, ViewSource& s, EventSink* k) : options(o), source(s), sink(k) {}

  void Run(std::promise<void>& ready) {
    std::unique_ptr<Canvas> canvas;
    try {
      canvas = std::make_unique<Canvas>(options);
      if (!options.record.empty()) {
        recorder = std::make_unique<Mp4Recorder>(options.record, options.width, options.height,
                                                 options.record_fps);
      }
      if (sink != nullptr && options.mode == ViewMode::kWindow) {
        sink->OnWindowOpened(&canvas->window(), options.width, options.height);
        // The window's events are the person's hands (the mouse device):
        // handed on late, a held key moves the key hand for as long as the
        // thread waited. Asked now, after the GL context started its own
        // threads (llvmpipe's rasterisers), which would inherit it.
        realtime = TryRealtime(options.realtime_priority);
      }
      ready.set_value();
    } catch (...) {
      canvas.reset();
      ready.set_exception(std::current_exception());
      return;
    }

    Loop(*canvas);
    if (sink != nullptr && options.mode == ViewMode::kWindow) sink->OnWindowClosed();

    if (recorder) recorder->Finish();
  }

  void Loop(Canvas& canvas) {
    Renderer& renderer = canvas.renderer();
    ViewModel model;
    model.shapes.reserve(256);
    cv::Mat readback;
    const auto period_ns = static_cast<int64_t>(1e9 / options.rate_hz);
    const double record_period_s = 1.0 / options.record_fps;
    const int64_t t0 = Now(CLOCK_MONOTONIC);
    const int64_t cpu0 = Now(CLOCK_THREAD_CPUTIME_ID);
    int64_t next = t0;
    uint64_t recorded_ticks = 0;
    uint64_t last_video_id = 0;
    while (!stop.load()) {
      PumpEvents();
      const int64_t start = Now(CLOCK_MONOTONIC);
      const int64_t cpu_start = Now(CLOCK_THREAD_CPUTIME_ID);
      const double t_s = static_cast<double>(start - t0) * 1e-9;
      source.Fill(model);
      renderer.Draw(model, t_s);
      // Read back before the swap: the back buffer is what was just drawn.
      const auto due_ticks = static_cast<uint64_t>(t_s / record_period_s) + 1;
      const bool tick_due = due_ticks > recorded_ticks;
      const bool record_now = recorder != nullptr && tick_due;
      if (record_now) renderer.ReadPixelsRaw(readback);
      WaitForFrameDrawn();
      canvas.Swap();
      int copies = static_cast<int>(std::min<uint64_t>(due_ticks - recorded_ticks, 30));
      // The tap's frames are the MP4's: those the encoder dropped are not in it.
      if (record_now) copies = recorder->Push(readback, copies);
      if (tick_due && options.tap != nullptr) options.tap->OnFrame(model, t_s, copies);
      const int64_t shown = Now(CLOCK_MONOTONIC);
      const int64_t shown_wall = Now(CLOCK_REALTIME);
      if (tick_due) recorded_ticks = due_ticks;
      frame_us.Record(static_cast<double>(shown - start) * 1e-3);
      frames.fetch_add(1);
      if (model.video.image && model.video.id != last_video_id) {
        last_video_id = model.video.id;
        video_frames_shown.fetch_add(1);
        if (model.video.capture_wall_ns > 0 && !model.video.stale) {
          video_to_screen_us.Record(static_cast<double>(shown_wall - model.video.capture_wall_ns) *
                                    1e-3);
        }
      }
      fps.store(static_cast<double>(frames.load()) * 1e9 /
                static_cast<double>(std::max<int64_t>(shown - t0, 1)));
      cpu_share.store(static_cast<double>(Now(CLOCK_THREAD_CPUTIME_ID) - cpu0) /
                      static_cast<double>(std::max<int64_t>(shown - t0, 1)));
      // A frame that took this thread ten periods of its own CPU is no
      // real-time work: at SCHED_FIFO it would hold a core from the rest.
      // Given up for good, as the physics and session threads give it up.
      // (Waiting for llvmpipe's rasterisers is not counted: they run apart.)
      if (realtime && Now(CLOCK_THREAD_CPUTIME_ID) - cpu_start > 10 * period_ns) {
        sched_param normal{};
        pthread_setschedparam(pthread_self(), SCHED_OTHER, &normal);
        realtime = false;
      }
      next += period_ns;
      const int64_t now = Now(CLOCK_MONOTONIC);
      if (next < now - period_ns) next = now;  // fell behind: do not race to catch up
      WaitForEventsUntil(next);
    }
  }

  /// The events SDL has now, each handed to the sink.
  void PumpEvents() {
    SDL_Event event;
    while (SDL_PollEvent(&event) != 0) {
      if (sink != nullptr) sink->OnEvent(event);
    }
  }

  /// Until the frame just drawn is rasterised, a window's events handed on
  /// each millisecond: the GL draws it on threads of its own (llvmpipe's, a
  /// GPU), and the swap would otherwise wait for it with the events queued.
  void WaitForFrameDrawn() {
    if (sink == nullptr || options.mode != ViewMode::kWindow) return;  // the swap waits
    GLsync drawn = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    if (drawn == nullptr) return;
    glFlush();
    while (glClientWaitSync(drawn, 0, 1'000'000) == GL_TIMEOUT_EXPIRED) PumpEvents();
    glDeleteSync(drawn);
  }

  /// Until `until_ns`, a window's events handed on as they come rather than
  /// at the next frame: the mouse device reads the pointer every servo tick,
  /// so the frame's wait would be the pointer's latency (SDL waits on the X
  /// connection's socket; with a joystick open it polls every millisecond).
  /// Offscreen, nobody points: a plain sleep.
  void WaitForEventsUntil(int64_t until_ns) {
    if (sink == nullptr || options.mode != ViewMode::kWindow) {
      SleepUntil(until_ns);
      return;
    }
    for (int64_t left = until_ns - Now(CLOCK_MONOTONIC); left >= 1'000'000;
         left = until_ns - Now(CLOCK_MONOTONIC)) {
      SDL_Event event;
      if (SDL_WaitEventTimeout(&event, static_cast<int>(left / 1'000'000)) != 0)
        sink->OnEvent(event);
    }
    SleepUntil(until_ns);
  }
};

View::View(const ViewOptions& options, ViewSource& source, EventSink* sink)
    : impl_(std::make_unique<Impl>(options, source, sink)) {
  if (options.width <= 0 || options.height <= 0 || options.width % 2 != 0 ||
      options.height % 2 != 0) {
    throw ViewError("view: width and height must be positive and even (H.264), got " +
                    std::to_string(options.width) + "x" + std::to_string(options.height));
  }
  if (!(options.rate_hz > 0) || !(options.record_fps > 0))
    throw ViewError("view: rate_hz and record_fps must be > 0");
  std::promise<void> ready;
  std::future<void> up = ready.get_future();
  impl_->thread = std::thread([this, &ready] { impl_->Run(ready); });
  try {
    up.get();
  } catch (...) {
    impl_->thread.join();
    throw;
  }
}

View::~View() { Stop(); }

void View::Stop() {
  impl_->stop.store(true);
  if (impl_->thread.joinable()) impl_->thread.join();
}

ViewStats View::Stats() const {
  const Impl& i = *impl_;
  ViewStats s;
  s.frames = i.frames.load();
  s.fps = i.fps.load();
  s.frame_ms_p50 = i.frame_us.Percentile(0.5) * 1e-3;
  s.frame_ms_p99 = i.frame_us.Percentile(0.99) * 1e-3;
  s.cpu_share = i.cpu_share.load();
  s.video_frames_shown = i.video_frames_shown.load();
  s.video_to_screen_ms_p50 = i.video_to_screen_us.Percentile(0.5) * 1e-3;
  s.video_to_screen_ms_p99 = i.video_to_screen_us.Percentile(0.99) * 1e-3;
  if (i.recorder) {
    s.recorded_frames = i.recorder->written();
    s.record_dropped = i.recorder->dropped();
    s.record_error = i.recorder->error();
  }
  return s;
}

}  // namespace haptel::view
