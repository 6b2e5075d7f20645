#pragma once
/// @file The X display a test or a benchmark drives as a person would: find
/// a window by its title, move the real pointer over it, press its buttons
/// and keys (XTest, what xdotool uses), and read back what it shows.
///
/// One connection per object, used from one thread. DISPLAY says which
/// server (the test's own Xvfb: tests/e2e/xserver.hpp). Xlib stays in the
/// .cpp: its macros (Success, None, Status) break Eigen and others.
#include <memory>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

struct _XDisplay;

namespace haptel::testing {

/// A top-level window and its size, pixels.
struct XWindowInfo {
  unsigned long id = 0;
  int width_px = 0;
  int height_px = 0;
};

class XDesktop {
 public:
  /// Connects to DISPLAY; std::runtime_error naming it when it cannot, or
  /// when the server has no XTest extension.
  XDesktop();

  /// The first window whose title begins with `title`, with its size now;
  /// nothing when there is none (yet).
  std::optional<XWindowInfo> FindWindow(const std::string& title);
  /// The window's size now (it may have been resized).
  XWindowInfo Refresh(const XWindowInfo& window);
  /// Gives `window` the keyboard (there is no window manager under Xvfb).
  void Focus(const XWindowInfo& window);

  /// Moves the pointer to (x, y) from `window`'s top-left corner (outside
  /// the window too: negative or past its size).
  void MovePointer(const XWindowInfo& window, int x_px, int y_px);
  /// Moves the pointer to the screen's top-left corner, off a window
  /// centred on it (a window that opens under the pointer has the mouse
  /// device's hand follow it at once, from wherever it rests).
  void ParkPointer();
  /// Moves the pointer to (x, y) from the screen's top-left corner (where
  /// a window will open, before it does).
  void MovePointerOnScreen(int x_px, int y_px);
  /// Presses (`down`) or releases X button `button` (1 left, 4/5 the wheel).
  void Button(unsigned button, bool down);
  /// One wheel notch: away from the user (`away`) or towards.
  void WheelNotch(bool away);
  /// Presses or releases the key of `keysym` (XK_w, ...).
  void Key(unsigned long keysym, bool down);
  /// Sends what was queued.
  void Flush();

  /// What `window` shows now, BGR.
  cv::Mat Capture(const XWindowInfo& window);

 private:
  struct Close {
    void operator()(_XDisplay* d) const;
  };
  std::unique_ptr<_XDisplay, Close> display_;
};

}  // namespace haptel::testing
