#pragma once
// A GL 3.3 core context for renderer tests (SDL's offscreen driver, Mesa),
// and where a point of the camera's picture lands in the rendered frame.
#include <SDL2/SDL.h>

#include <array>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <opencv2/core.hpp>

#include "haptel/view/renderer.hpp"

namespace haptel::test {

/// A hidden window with a GL 3.3 core context current on this thread.
class OffscreenGl {
 public:
  OffscreenGl(int width, int height) {
    setenv("SDL_VIDEODRIVER", "offscreen", 1);
    REQUIRE(SDL_Init(SDL_INIT_VIDEO) == 0);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_CORE);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, 3);
    SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, 3);
    SDL_GL_SetAttribute(SDL_GL_DEPTH_SIZE, 24);
    window_ = SDL_CreateWindow("test", 0, 0, width, height, SDL_WINDOW_OPENGL | SDL_WINDOW_HIDDEN);
    REQUIRE(window_ != nullptr);
    context_ = SDL_GL_CreateContext(window_);
    INFO(SDL_GetError());
    REQUIRE(context_ != nullptr);
  }
  ~OffscreenGl() {
    SDL_GL_DeleteContext(context_);
    SDL_DestroyWindow(window_);
    SDL_Quit();
    unsetenv("SDL_VIDEODRIVER");
  }
  OffscreenGl(const OffscreenGl&) = delete;
  OffscreenGl& operator=(const OffscreenGl&) = delete;

 private:
  SDL_Window* window_ = nullptr;
  SDL_GLContext context_ = nullptr;
};

/// The image point of (u, v) ∈ [0,1]² on the screen (u right, v down, as the
/// operator sees it), from the renderer's own screen corners and projection.
inline cv::Point ScreenPoint(const view::Renderer& r, double u, double v) {
  const auto c = r.ScreenCorners();  // top-left, top-right, bottom-right, bottom-left
  std::array<double, 3> p{};
  for (int k = 0; k < 3; ++k) {
    const double top = c[0][k] + u * (c[1][k] - c[0][k]);
    const double bottom = c[3][k] + u * (c[2][k] - c[3][k]);
    p[k] = top + v * (bottom - top);
  }
  double px = 0, py = 0;
  REQUIRE(r.Project(p, px, py));
  return {static_cast<int>(px), static_cast<int>(py)};
}

/// The pixel at `p`, which must be inside `bgr`.
inline cv::Vec3b At(const cv::Mat& bgr, cv::Point p) {
  REQUIRE(p.x >= 0);
  REQUIRE(p.y >= 0);
  REQUIRE(p.x < bgr.cols);
  REQUIRE(p.y < bgr.rows);
  return bgr.at<cv::Vec3b>(p);
}

}  // namespace haptel::test
