#pragma once
/// @file Where the view draws: SDL's video, a window (shown, or hidden on
/// SDL's offscreen driver) with an OpenGL 3.3 core context current on the
/// calling thread, and the Renderer on it. The live view's thread opens one
/// (view.hpp); `haptel replay --mp4` opens one offscreen and draws each
/// frame itself, as fast as it can: the same context, the same renderer,
/// the same pixels.
#include <memory>

#include "haptel/view/renderer.hpp"
#include "haptel/view/view.hpp"

struct SDL_Window;

namespace haptel::view {

class Canvas {
 public:
  /// Starts SDL's video (and game controllers), opens the window and the
  /// context, and builds the renderer for `options`' size and screen. Throws
  /// ViewError when it cannot (no display for a window, no GL 3.3).
  explicit Canvas(const ViewOptions& options);
  /// Releases the renderer, the context and the window, and SDL's video
  /// (SDL itself only when nothing else uses it).
  ~Canvas();
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;

  Renderer& renderer() { return *renderer_; }
  SDL_Window& window() { return *window_; }
  /// Shows the frame drawn (the back buffer) and waits until it is done.
  void Swap();

 private:
  SDL_Window* window_ = nullptr;
  void* context_ = nullptr;  ///< SDL_GLContext
  std::unique_ptr<Renderer> renderer_;
};

}  // namespace haptel::view
