#include "haptel/testing/x_desktop.hpp"

#include <X11/Xlib.h>
#include <X11/Xutil.h>
#include <X11/extensions/XTest.h>

#include <cstdlib>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace haptel::testing {
namespace {

std::string TitleOf(Display* d, Window w) {
  char* name = nullptr;
  if (XFetchName(d, w, &name) == 0 || name == nullptr) return {};
  std::string title(name);
  XFree(name);
  return title;
}

/// Depth first from `w`: the first window whose title begins with `title`.
Window FindByTitle(Display* d, Window w, const std::string& title) {
  if (const std::string t = TitleOf(d, w); !t.empty() && t.rfind(title, 0) == 0) return w;
  Window root = 0, parent = 0;
  Window* children = nullptr;
  unsigned n = 0;
  if (XQueryTree(d, w, &root, &parent, &children, &n) == 0) return 0;
  Window found = 0;
  for (unsigned i = 0; i < n && found == 0; ++i) found = FindByTitle(d, children[i], title);
  if (children != nullptr) XFree(children);
  return found;
}

/// Xlib's default handler ends the process on any error; a window that went
/// away (its run ended) while the pilot still moved over it is no reason to.
int KeepGoing(Display*, XErrorEvent*) { return 0; }

}  // namespace

void XDesktop::Close::operator()(_XDisplay* d) const { XCloseDisplay(d); }

XDesktop::XDesktop() : display_(XOpenDisplay(nullptr)) {
  const char* name = std::getenv("DISPLAY");
  if (!display_) {
    throw std::runtime_error(std::string("cannot open the X display '") +
                             (name != nullptr ? name : "") + "' (DISPLAY)");
  }
  XSetErrorHandler(KeepGoing);
  int event = 0, error = 0, major = 0, minor = 0;
  if (!XTestQueryExtension(display_.get(), &event, &error, &major, &minor)) {
    throw std::runtime_error(std::string("the X display '") + (name != nullptr ? name : "") +
                             "' has no XTest extension: cannot move its pointer");
  }
}

std::optional<XWindowInfo> XDesktop::FindWindow(const std::string& title) {
  Display* d = display_.get();
  const Window w = FindByTitle(d, DefaultRootWindow(d), title);
  if (w == 0) return std::nullopt;
  return Refresh({w, 0, 0});
}

XWindowInfo XDesktop::Refresh(const XWindowInfo& window) {
  XWindowAttributes a{};
  if (XGetWindowAttributes(display_.get(), window.id, &a) == 0) return window;
  return {window.id, a.width, a.height};
}

void XDesktop::Focus(const XWindowInfo& window) {
  XSetInputFocus(display_.get(), window.id, RevertToPointerRoot, CurrentTime);
  Flush();
}

void XDesktop::MovePointer(const XWindowInfo& window, int x_px, int y_px) {
  Display* d = display_.get();
  int root_x = 0, root_y = 0;
  Window child = 0;
  XTranslateCoordinates(d, window.id, DefaultRootWindow(d), x_px, y_px, &root_x, &root_y, &child);
  XTestFakeMotionEvent(d, DefaultScreen(d), root_x, root_y, CurrentTime);
  Flush();
}

void XDesktop::ParkPointer() { MovePointerOnScreen(0, 0); }

void XDesktop::MovePointerOnScreen(int x_px, int y_px) {
  Display* d = display_.get();
  XTestFakeMotionEvent(d, DefaultScreen(d), x_px, y_px, CurrentTime);
  XSync(d, False);  // moved when this returns: a window opened next opens under it
}

void XDesktop::Button(unsigned button, bool down) {
  XTestFakeButtonEvent(display_.get(), button, down ? True : False, CurrentTime);
  Flush();
}

void XDesktop::WheelNotch(bool away) {
  // X's buttons 4 and 5 are the wheel's notches (up: away from the user).
  Button(away ? 4 : 5, true);
  Button(away ? 4 : 5, false);
}

void XDesktop::Key(unsigned long keysym, bool down) {
  Display* d = display_.get();
  const KeyCode code = XKeysymToKeycode(d, keysym);
  if (code == 0)
    throw std::runtime_error("the X display has no key for keysym " + std::to_string(keysym));
  XTestFakeKeyEvent(d, code, down ? True : False, CurrentTime);
  Flush();
}

void XDesktop::Flush() { XFlush(display_.get()); }

cv::Mat XDesktop::Capture(const XWindowInfo& window) {
  const XWindowInfo now = Refresh(window);
  XImage* image = XGetImage(display_.get(), now.id, 0, 0, static_cast<unsigned>(now.width_px),
                            static_cast<unsigned>(now.height_px), AllPlanes, ZPixmap);
  if (image == nullptr) throw std::runtime_error("cannot read the window's picture (XGetImage)");
  if (image->bits_per_pixel != 32) {
    XDestroyImage(image);
    throw std::runtime_error("the X screen is not 24-bit in 32-bit pixels (Xvfb -screen 0 WxHx24)");
  }
  // Blue in the low byte (BGRX).
  const cv::Mat bgrx(now.height_px, now.width_px, CV_8UC4, image->data,
                     static_cast<size_t>(image->bytes_per_line));
  cv::Mat bgr;
  cv::cvtColor(bgrx, bgr, cv::COLOR_BGRA2BGR);
  XDestroyImage(image);
  return bgr;
}

}  // namespace haptel::testing
