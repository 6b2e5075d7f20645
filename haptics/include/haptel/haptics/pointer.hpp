#pragma once
/// @file The desktop's pointer and the keys that move a mouse device's key
/// hand, as the view's window saw them last, and the `mouse` device's map
/// from them to its hands' targets (config: MouseDeviceConfig).
///
/// One writer: the thread that polls SDL (the view thread) stores every
/// change into DesktopPointer(); the mouse device's servo thread loads it
/// each tick. A seqlock: neither waits for the other.
#include <array>
#include <cstdint>

#include "haptel/config/device.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

/// Keys of the key hand, in the order of PointerState::key_hand.
enum class KeyHandKey : int { kPlusX, kMinusX, kPlusY, kMinusY, kPlusZ, kMinusZ, kCount };

struct PointerState {
  bool window_open = false;  ///< a window reports the pointer (else nothing is known)
  bool in_window = false;    ///< the pointer is inside it (SDL's enter/leave)
  int x_px = 0;              ///< from the window's left edge
  int y_px = 0;              ///< from the window's top edge (SDL's: y grows downward)
  int width_px = 0;          ///< the window's size now
  int height_px = 0;
  bool grasp_button = false;  ///< the left button is down
  int64_t wheel_notches = 0;  ///< the scroll wheel's notches so far, + away from the user
  /// Held keys of the key hand (W/S, A/D, Q/E and the arrows), KeyHandKey order.
  std::array<bool, static_cast<int>(KeyHandKey::kCount)> key_hand{};
  uint64_t events = 0;  ///< changes stored so far
  int64_t t_ns = 0;     ///< CLOCK_MONOTONIC of the last change
};

/// The desktop's one pointer (a process has one view window).
class PointerBox {
 public:
  void Store(const PointerState& state) { state_.Store(state); }
  PointerState Load() const { return state_.Load(); }
  /// For the servo thread: a few attempts, then false with `out` untouched
  /// (the writer was pre-empted mid-store; the caller keeps its last value).
  bool TryLoad(PointerState& out) const { return state_.TryLoad(out, 4); }

 private:
  Seqlock<PointerState> state_;
};

/// The box the view stores into and the mouse device reads.
PointerBox& DesktopPointer();

/// Where the pointer puts the pointer hand, device metres: the window's
/// centre at `config.centre`, up +x, right −y, the wheel's notches in z.
Vec3d PointerTarget(const PointerState& pointer, const MouseDeviceConfig& config);

/// The pixel (x, y) that puts the pointer hand at `target`'s x and y for a
/// window of `width_px` × `height_px` (PointerTarget's inverse; its z is the
/// wheel's, not the pixel's). Rounded to the nearest pixel.
std::array<int, 2> PointerPixelFor(const Vec3d& target, const MouseDeviceConfig& config,
                                   int width_px, int height_px);

/// The key hand's target after `dt_s` from `now`: each held key moves it at
/// `key_hand_speed` along its axis; an axis with neither of its keys held
/// goes back to `key_hand_rest` at that speed (both held: it stays).
Vec3d StepKeyHand(const Vec3d& now, const PointerState& pointer, const MouseDeviceConfig& config,
                  double dt_s);

}  // namespace haptel::haptics
