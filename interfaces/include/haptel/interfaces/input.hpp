#pragma once
/// @file What a person presses: keyboard keys and a game controller, as one
/// trivially copyable value handed from the thread that owns the input
/// devices (the view, or an input pump when there is no view) to the session
/// thread through a seqlock (InputBox). Interfaces read it; they never see SDL.
#include <array>
#include <cstdint>

#include "haptel/core/seqlock.hpp"

namespace haptel::interfaces {

/// Buttons of a game controller, in SDL's GameController order.
enum class PadButton : int {
  kA = 0,
  kB,
  kX,
  kY,
  kBack,
  kGuide,
  kStart,
  kLeftStick,
  kRightStick,
  kLeftShoulder,
  kRightShoulder,
  kDpadUp,
  kDpadDown,
  kDpadLeft,
  kDpadRight,
  kCount
};
/// Axes of a game controller, in SDL's GameController order.
enum class PadAxis : int {
  kLeftX = 0,
  kLeftY,
  kRightX,
  kRightY,
  kTriggerLeft,
  kTriggerRight,
  kCount
};

/// The physical keys that drive, by position (scancode): the robot's
/// keyboard reads arrows and W/A/S/D as one set, the blimp's gives them
/// different jobs.
enum class Key : int {
  kArrowUp = 0,
  kArrowDown,
  kArrowLeft,
  kArrowRight,
  kW,
  kS,
  kA,
  kD,
  kSpace,
  kPageUp,
  kPageDown,
  kCount
};

/// InputState::vehicle_request asking for the vehicle after the driven one.
inline constexpr int kNextVehicle = -1;

struct InputState {
  // --- Keyboard: held now (arrows or W/A/S/D; space). ---
  bool key_up = false;
  bool key_down = false;
  bool key_left = false;
  bool key_right = false;
  bool key_stop = false;
  /// Presses so far (counters, so a press shorter than a session tick is
  /// still seen): the interface steps one level per press it has not seen.
  uint32_t presses_up = 0;
  uint32_t presses_down = 0;
  uint32_t presses_left = 0;
  uint32_t presses_right = 0;
  uint32_t presses_stop = 0;
  /// Each physical key on its own (Key): held now, and presses so far.
  std::array<bool, static_cast<int>(Key::kCount)> keys_held{};
  std::array<uint32_t, static_cast<int>(Key::kCount)> key_presses{};

  // --- Game controller (the first one SDL knows). ---
  bool pad_connected = false;
  /// Controllers that went away during the run (a disconnect mid-run aborts).
  uint32_t pad_disconnects = 0;
  /// Sticks in [-1, 1] with SDL's sign (y down is +); triggers in [0, 1].
  std::array<double, static_cast<int>(PadAxis::kCount)> pad_axes{};
  std::array<bool, static_cast<int>(PadButton::kCount)> pad_buttons{};

  // --- Mouse-look: where the person's head turns (the view's window). ---
  /// Dragging with a mouse button held turns the head (rad; pan positive
  /// left, tilt positive up, within the pilot camera's range); Home looks
  /// straight ahead again. Interfaces with a camera head follow it.
  double head_pan = 0.0;
  double head_tilt = 0.0;

  // --- Session requests. ---
  /// The window was closed (or the person asked to quit).
  bool quit = false;
  /// F1..F6 pressed: index 0..5 of the run's interface list; counted so
  /// each press is one request.
  int interface_request = -1;
  uint32_t interface_requests = 0;
  /// A fleet's vehicle asked for (haptel run --fleet): Tab or the
  /// controller's Back button ask for the next one (kNextVehicle), 1..9 for
  /// vehicle 0..8 of the fleet file; counted so each press is one request.
  int vehicle_request = -1;
  uint32_t vehicle_requests = 0;
};

/// Latest InputState: one writer (the input thread), any readers. Wait-free.
using InputBox = Seqlock<InputState>;

}  // namespace haptel::interfaces
