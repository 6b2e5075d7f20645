#pragma once
/// @file A person's keyboard and game controller, from SDL events to an
/// InputState in an InputBox (what the interfaces read; they never see SDL).
///
/// SdlInput is the view's EventSink: the thread that polls SDL (the view
/// thread, or an InputPump when there is no view) hands it every event, and
/// it publishes the updated state. It is the box's one writer.
///
/// Keys are read by scancode (physical position), so W/A/S/D sit where they
/// do on a QWERTY keyboard whatever the layout: arrows or W/A/S/D drive
/// (each key also on its own, with Page Up/Down, for the blimp's keys),
/// space stops, F1..F6 ask for interface 0..5 of the run, and closing the
/// window asks to quit. In a fleet, Tab or the controller's Back button ask
/// for the next vehicle and 1..9 for that vehicle of the fleet file. Dragging the mouse with the
/// right button held turns the head (mouse-look: kHeadRadPerPixel, clamped to the pilot camera's
/// range); Home looks straight ahead. The first game controller SDL reports is opened;
/// another one is ignored until it goes away.
///
/// It is also the writer of the desktop's pointer (haptel/haptics/pointer.hpp),
/// which the mouse device reads: every change of the pointer in the window
/// (its place, enter and leave, the left button that grasps, the wheel, the
/// window's size) and of the key hand's keys (W/S, A/D, Q/E, the arrows as
/// W/S/A/D) is stored there. F turns the force arrows on the hands on and off
/// (force_arrows()).
#include <SDL2/SDL.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>

#include "haptel/haptics/pointer.hpp"
#include "haptel/interfaces/input.hpp"
#include "haptel/view/view.hpp"

namespace haptel::view {

class SdlInput : public EventSink {
 public:
  /// Publishes into `box` (which must outlive this); starts from `box`'s
  /// current value so counters keep counting across sinks.
  explicit SdlInput(interfaces::InputBox& box);
  /// Stores the pointer into `pointer` (a test's own box) instead of the desktop's.
  SdlInput(interfaces::InputBox& box, haptics::PointerBox& pointer);
  /// Closes the controller if SDL's game controller subsystem is still up
  /// (after SDL_Quit SDL has freed it already).
  ~SdlInput() override;
  SdlInput(const SdlInput&) = delete;
  SdlInput& operator=(const SdlInput&) = delete;

  /// Allocation-free for key, axis, button and window events (opening a
  /// newly added controller is SDL's own allocation, once per device).
  void OnEvent(const SDL_Event& event) override;
  /// The pointer's window is open at this size. Where the pointer is is
  /// asked of the desktop (PlaceFromDesktop): a window that opens under a
  /// still pointer gets no motion to say so. `window` null (a test's): only
  /// events place it.
  void OnWindowOpened(SDL_Window* window, int width_px, int height_px) override;
  /// No window reports the pointer any more: the mouse device lets go.
  void OnWindowClosed() override;

  /// Whether the hands' force arrows are shown (F toggles; off at start).
  /// The view thread's, as the events are.
  bool force_arrows() const { return force_arrows_; }
  /// The pointer as last stored.
  const haptics::PointerState& pointer() const { return pointer_; }

  /// Closes the open controller and publishes pad_connected = false (not
  /// counted as a disconnect: it was let go on purpose). Call on the SDL
  /// thread before SDL_Quit.
  void Release();

  /// The state as last published (the writer thread's copy).
  const interfaces::InputState& state() const { return state_; }

  /// An SDL GameController axis value as InputState holds it: sticks in
  /// [-1, 1] (SDL's sign), triggers in [0, 1].
  static double AxisValue(int sdl_axis, int16_t raw);

  /// Mouse-look's turn per pixel dragged: 300 px turns the head 90°.
  static constexpr double kHeadRadPerPixel = 0.005236;

 private:
  void OnKey(const SDL_KeyboardEvent& key, bool down);
  void OnMouseMotion(const SDL_MouseMotionEvent& motion);
  /// Pointer events into pointer_; false when nothing of it changed.
  bool OnPointerEvent(const SDL_Event& event);
  /// The key hand's keys from the held keys (W/S/A/D and arrows, Q/E).
  void UpdateKeyHand();
  void StorePointer();
  /// The pointer's place (and whether it is in `window`) from the desktop's
  /// pointer now, not from an event: on open, and on entering or taking
  /// focus (a window that opened or rose under a still pointer).
  void PlaceFromDesktop(SDL_Window* window);
  void Place(int x_px, int y_px);
  void OnControllerAdded(int device_index);
  void OnControllerRemoved(SDL_JoystickID instance);
  void ClearPad();
  void Close();

  interfaces::InputBox& box_;
  interfaces::InputState state_;
  SDL_GameController* pad_ = nullptr;
  SDL_JoystickID pad_id_ = -1;
  haptics::PointerBox& pointer_box_;
  haptics::PointerState pointer_;
  bool key_up_z_ = false;    ///< Q held
  bool key_down_z_ = false;  ///< E held
  bool force_arrows_ = false;
};

/// For runs with a game controller and no view: a thread that owns SDL's
/// game controller subsystem and polls its events into an SdlInput at
/// ~100 Hz.
class InputPump {
 public:
  /// Starts the thread and waits for SDL_Init(SDL_INIT_GAMECONTROLLER) (with
  /// background joystick events allowed, so no window focus is needed).
  /// Throws std::runtime_error with SDL's message when it fails.
  explicit InputPump(interfaces::InputBox& box, double rate_hz = 100.0);
  /// Stop().
  ~InputPump();
  InputPump(const InputPump&) = delete;
  InputPump& operator=(const InputPump&) = delete;

  /// Closes the controller, shuts SDL down, joins. Idempotent.
  void Stop();

  /// Runs `fn` on the pump thread, between two polls, and waits for it
  /// (SDL calls that belong to the thread owning SDL: tests attach virtual
  /// controllers this way). Rethrows what `fn` throws.
  void RunOnPumpThread(const std::function<void()>& fn);

  /// Completed poll cycles: a test waits for "one more cycle after X".
  uint64_t polls() const { return polls_.load(std::memory_order_acquire); }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::atomic<uint64_t> polls_{0};
};

}  // namespace haptel::view
