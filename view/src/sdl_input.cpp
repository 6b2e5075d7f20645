#include "haptel/view/sdl_input.hpp"

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <exception>
#include <future>
#include <mutex>
#include <stdexcept>
#include <string>
#include <thread>

#include "haptel/core/blimp_command.hpp"
#include "haptel/core/clock.hpp"

namespace haptel::view {

using interfaces::InputState;
using interfaces::PadAxis;
using interfaces::PadButton;

// InputState's enums are documented as SDL's order; hold them to it.
static_assert(static_cast<int>(PadAxis::kLeftX) == SDL_CONTROLLER_AXIS_LEFTX);
static_assert(static_cast<int>(PadAxis::kTriggerRight) == SDL_CONTROLLER_AXIS_TRIGGERRIGHT);
static_assert(static_cast<int>(PadAxis::kCount) == SDL_CONTROLLER_AXIS_MAX);
static_assert(static_cast<int>(PadButton::kA) == SDL_CONTROLLER_BUTTON_A);
static_assert(static_cast<int>(PadButton::kLeftShoulder) == SDL_CONTROLLER_BUTTON_LEFTSHOULDER);
static_assert(static_cast<int>(PadButton::kDpadRight) == SDL_CONTROLLER_BUTTON_DPAD_RIGHT);
static_assert(static_cast<int>(PadButton::kCount) == SDL_CONTROLLER_BUTTON_MISC1);

SdlInput::SdlInput(interfaces::InputBox& box) : SdlInput(box, haptics::DesktopPointer()) {}

SdlInput::SdlInput(interfaces::InputBox& box, haptics::PointerBox& pointer)
    : box_(box), state_(box.Load()), pointer_box_(pointer), pointer_(pointer.Load()) {
  // A fresh sink owns no controller and holds no key, whatever was before.
  ClearPad();
  state_.pad_connected = false;
  state_.key_up = state_.key_down = state_.key_left = state_.key_right = state_.key_stop = false;
  state_.keys_held = {};
  pointer_.key_hand = {};
}

void SdlInput::OnWindowOpened(SDL_Window* window, int width_px, int height_px) {
  pointer_.window_open = true;
  pointer_.width_px = width_px;
  pointer_.height_px = height_px;
  pointer_.in_window = false;
  // A press is taken only in the window: a button already down as it opens
  // (a study's next trial) does not grasp.
  pointer_.grasp_button = false;
  PlaceFromDesktop(window);
  // A new window's hand starts at its rest height: the notches of the last
  // one (a study's previous trial, in this process) would put it above or
  // below, and a person (or the pointer pilot) starts counting from there.
  pointer_.wheel_notches = 0;
  StorePointer();
}

void SdlInput::OnWindowClosed() {
  pointer_.window_open = false;
  pointer_.in_window = false;
  pointer_.grasp_button = false;
  // The key hand's keys go with the window (no window reports their
  // release): held on in the box, they walked the next mouse device's key
  // hand away at its speed from the device's start to its window's (a
  // study's next trial, in this process), and it swept back through the
  // cockpit's wheel, turning it off zero.
  pointer_.key_hand = {};
  key_up_z_ = key_down_z_ = false;
  StorePointer();
}

void SdlInput::StorePointer() {
  ++pointer_.events;
  pointer_.t_ns = MonotonicNs();
  pointer_box_.Store(pointer_);
}

void SdlInput::UpdateKeyHand() {
  using haptics::KeyHandKey;
  using interfaces::Key;
  const auto held = [this](Key k) { return state_.keys_held[static_cast<size_t>(k)]; };
  const auto set = [this](KeyHandKey k, bool on) {
    pointer_.key_hand[static_cast<size_t>(k)] = on;
  };
  set(KeyHandKey::kPlusX, held(Key::kW) || held(Key::kArrowUp));
  set(KeyHandKey::kMinusX, held(Key::kS) || held(Key::kArrowDown));
  set(KeyHandKey::kPlusY, held(Key::kA) || held(Key::kArrowLeft));
  set(KeyHandKey::kMinusY, held(Key::kD) || held(Key::kArrowRight));
  set(KeyHandKey::kPlusZ, key_up_z_);
  set(KeyHandKey::kMinusZ, key_down_z_);
}

// The pointer is in the window when it is inside its bounds (a drag that
// leaves the window keeps reporting, from outside).
void SdlInput::Place(int x_px, int y_px) {
  pointer_.x_px = x_px;
  pointer_.y_px = y_px;
  if (pointer_.width_px > 0 && pointer_.height_px > 0) {
    pointer_.in_window =
        x_px >= 0 && y_px >= 0 && x_px < pointer_.width_px && y_px < pointer_.height_px;
  }
}

void SdlInput::PlaceFromDesktop(SDL_Window* window) {
  if (window == nullptr) return;
  // SDL's own idea of the pointer moves only with its events; the desktop's
  // (X: XQueryPointer) is where it is now. Both in screen pixels.
  int screen_x = 0, screen_y = 0, window_x = 0, window_y = 0;
  SDL_GetGlobalMouseState(&screen_x, &screen_y);
  SDL_GetWindowPosition(window, &window_x, &window_y);
  Place(screen_x - window_x, screen_y - window_y);
}

bool SdlInput::OnPointerEvent(const SDL_Event& event) {
  switch (event.type) {
    case SDL_MOUSEMOTION:
      Place(event.motion.x, event.motion.y);
      return true;
    case SDL_MOUSEBUTTONDOWN:
    case SDL_MOUSEBUTTONUP:
      Place(event.button.x, event.button.y);
      if (event.button.button == SDL_BUTTON_LEFT)
        pointer_.grasp_button = event.type == SDL_MOUSEBUTTONDOWN;
      return true;
    case SDL_MOUSEWHEEL:
      pointer_.wheel_notches +=
          event.wheel.direction == SDL_MOUSEWHEEL_FLIPPED ? -event.wheel.y : event.wheel.y;
      return true;
    case SDL_WINDOWEVENT:
      switch (event.window.event) {
        case SDL_WINDOWEVENT_ENTER:
        case SDL_WINDOWEVENT_FOCUS_GAINED:
          // Entered (or raised) with no motion yet: the place is the
          // desktop's, else the last one stored (another window's, or none).
          pointer_.in_window = event.window.event == SDL_WINDOWEVENT_ENTER || pointer_.in_window;
          PlaceFromDesktop(SDL_GetWindowFromID(event.window.windowID));
          return true;
        case SDL_WINDOWEVENT_LEAVE:
          pointer_.in_window = false;
          return true;
        case SDL_WINDOWEVENT_SIZE_CHANGED:
        case SDL_WINDOWEVENT_RESIZED:
          pointer_.width_px = event.window.data1;
          pointer_.height_px = event.window.data2;
          return true;
        default:
          return false;
      }
    default:
      return false;
  }
}

SdlInput::~SdlInput() {
  if (pad_ != nullptr && SDL_WasInit(SDL_INIT_GAMECONTROLLER) != 0) SDL_GameControllerClose(pad_);
}

void SdlInput::Close() {
  if (pad_ != nullptr) SDL_GameControllerClose(pad_);
  pad_ = nullptr;
  pad_id_ = -1;
}

void SdlInput::Release() {
  const bool had_pad = pad_ != nullptr;
  Close();
  if (!had_pad) return;
  // Let go on purpose: no controller any more, but not a disconnect.
  ClearPad();
  state_.pad_connected = false;
  box_.Store(state_);
}

double SdlInput::AxisValue(int sdl_axis, int16_t raw) {
  // SDL's range is asymmetric (−32768..32767): divide by the positive end
  // and clamp, so both full deflections are exactly ±1.
  const double v = std::clamp(static_cast<double>(raw) / 32767.0, -1.0, 1.0);
  const bool trigger =
      sdl_axis == SDL_CONTROLLER_AXIS_TRIGGERLEFT || sdl_axis == SDL_CONTROLLER_AXIS_TRIGGERRIGHT;
  return trigger ? std::max(0.0, v) : v;
}

void SdlInput::ClearPad() {
  state_.pad_axes = {};
  state_.pad_buttons = {};
}

void SdlInput::OnKey(const SDL_KeyboardEvent& key, bool down) {
  using interfaces::Key;
  // The mouse device's key hand: Q/E up and down (W/S/A/D and the arrows below).
  if (key.keysym.scancode == SDL_SCANCODE_Q || key.keysym.scancode == SDL_SCANCODE_E) {
    (key.keysym.scancode == SDL_SCANCODE_Q ? key_up_z_ : key_down_z_) = down;
    UpdateKeyHand();
    StorePointer();
    return;
  }
  if (down && key.repeat == 0 && key.keysym.scancode == SDL_SCANCODE_F) {
    force_arrows_ = !force_arrows_;
    return;
  }
  Key which = Key::kCount;
  uint32_t InputState::*presses = nullptr;  // the robot's counter: arrows and W/A/S/D are one set
  switch (key.keysym.scancode) {
    case SDL_SCANCODE_UP:
      which = Key::kArrowUp;
      presses = &InputState::presses_up;
      break;
    case SDL_SCANCODE_W:
      which = Key::kW;
      presses = &InputState::presses_up;
      break;
    case SDL_SCANCODE_DOWN:
      which = Key::kArrowDown;
      presses = &InputState::presses_down;
      break;
    case SDL_SCANCODE_S:
      which = Key::kS;
      presses = &InputState::presses_down;
      break;
    case SDL_SCANCODE_LEFT:
      which = Key::kArrowLeft;
      presses = &InputState::presses_left;
      break;
    case SDL_SCANCODE_A:
      which = Key::kA;
      presses = &InputState::presses_left;
      break;
    case SDL_SCANCODE_RIGHT:
      which = Key::kArrowRight;
      presses = &InputState::presses_right;
      break;
    case SDL_SCANCODE_D:
      which = Key::kD;
      presses = &InputState::presses_right;
      break;
    case SDL_SCANCODE_SPACE:
      which = Key::kSpace;
      presses = &InputState::presses_stop;
      break;
    case SDL_SCANCODE_PAGEUP:
      which = Key::kPageUp;
      break;
    case SDL_SCANCODE_PAGEDOWN:
      which = Key::kPageDown;
      break;
    default:
      break;
  }
  if (which != Key::kCount) {
    const auto i = static_cast<size_t>(which);
    state_.keys_held[i] = down;
    // Auto-repeat key-downs are not presses: the interface times its own
    // repeats from the held flag, at its configured rate.
    if (down && key.repeat == 0) {
      ++state_.key_presses[i];
      if (presses != nullptr) ++(state_.*presses);
    }
    const auto held = [this](Key k) { return state_.keys_held[static_cast<size_t>(k)]; };
    state_.key_up = held(Key::kArrowUp) || held(Key::kW);
    state_.key_down = held(Key::kArrowDown) || held(Key::kS);
    state_.key_left = held(Key::kArrowLeft) || held(Key::kA);
    state_.key_right = held(Key::kArrowRight) || held(Key::kD);
    state_.key_stop = held(Key::kSpace);
    UpdateKeyHand();
    StorePointer();
    return;
  }
  if (down && key.repeat == 0 && key.keysym.scancode >= SDL_SCANCODE_F1 &&
      key.keysym.scancode <= SDL_SCANCODE_F6) {
    state_.interface_request = key.keysym.scancode - SDL_SCANCODE_F1;
    ++state_.interface_requests;
  }
  // A fleet's vehicles: Tab the next, 1..9 that one of the fleet file.
  if (down && key.repeat == 0 && key.keysym.scancode == SDL_SCANCODE_TAB) {
    state_.vehicle_request = interfaces::kNextVehicle;
    ++state_.vehicle_requests;
  }
  if (down && key.repeat == 0 && key.keysym.scancode >= SDL_SCANCODE_1 &&
      key.keysym.scancode <= SDL_SCANCODE_9) {
    state_.vehicle_request = key.keysym.scancode - SDL_SCANCODE_1;
    ++state_.vehicle_requests;
  }
  if (down && key.keysym.scancode == SDL_SCANCODE_HOME) {
    state_.head_pan = 0.0;
    state_.head_tilt = 0.0;
  }
  // Escape ends the run as closing the window does: what was measured is kept.
  if (down && key.keysym.scancode == SDL_SCANCODE_ESCAPE) state_.quit = true;
}

void SdlInput::OnMouseMotion(const SDL_MouseMotionEvent& motion) {
  // Dragging right looks right (pan is positive left); dragging up looks up
  // (SDL's y grows downward). The range is the pilot camera's: a head that
  // could turn past it would have to drag back over nothing.
  state_.head_pan = std::clamp(state_.head_pan - motion.xrel * kHeadRadPerPixel,
                               -kBlimpCameraPanMax, kBlimpCameraPanMax);
  state_.head_tilt = std::clamp(state_.head_tilt - motion.yrel * kHeadRadPerPixel,
                                -kBlimpCameraTiltMax, kBlimpCameraTiltMax);
}

void SdlInput::OnControllerAdded(int device_index) {
  if (pad_ != nullptr) return;  // the first controller drives; others wait
  SDL_GameController* pad = SDL_GameControllerOpen(device_index);
  if (pad == nullptr) return;
  pad_ = pad;
  pad_id_ = SDL_JoystickInstanceID(SDL_GameControllerGetJoystick(pad));
  ClearPad();
  state_.pad_connected = true;
}

void SdlInput::OnControllerRemoved(SDL_JoystickID instance) {
  if (pad_ == nullptr || instance != pad_id_) return;
  Close();
  ClearPad();
  state_.pad_connected = false;
  ++state_.pad_disconnects;
}

void SdlInput::OnEvent(const SDL_Event& event) {
  if (OnPointerEvent(event)) StorePointer();
  switch (event.type) {
    case SDL_KEYDOWN:
    case SDL_KEYUP:
      OnKey(event.key, event.type == SDL_KEYDOWN);
      break;
    case SDL_MOUSEMOTION:
      // Mouse-look is the right button's: the left one grasps (the mouse device).
      if ((event.motion.state & SDL_BUTTON_RMASK) == 0) return;
      OnMouseMotion(event.motion);
      break;
    case SDL_CONTROLLERDEVICEADDED:
      OnControllerAdded(event.cdevice.which);  // a device index here
      break;
    case SDL_CONTROLLERDEVICEREMOVED:
      OnControllerRemoved(event.cdevice.which);  // an instance id here
      break;
    case SDL_CONTROLLERAXISMOTION:
      if (pad_ == nullptr || event.caxis.which != pad_id_) return;
      if (event.caxis.axis >= static_cast<int>(PadAxis::kCount)) return;
      state_.pad_axes[event.caxis.axis] = AxisValue(event.caxis.axis, event.caxis.value);
      break;
    case SDL_CONTROLLERBUTTONDOWN:
    case SDL_CONTROLLERBUTTONUP:
      if (pad_ == nullptr || event.cbutton.which != pad_id_) return;
      if (event.cbutton.button >= static_cast<int>(PadButton::kCount)) return;
      // Back (the "view" button) asks for the fleet's next vehicle: no
      // interface drives with it, so a switch never doubles as a command.
      if (event.cbutton.button == SDL_CONTROLLER_BUTTON_BACK &&
          event.cbutton.state == SDL_PRESSED && !state_.pad_buttons[event.cbutton.button]) {
        state_.vehicle_request = interfaces::kNextVehicle;
        ++state_.vehicle_requests;
      }
      state_.pad_buttons[event.cbutton.button] = event.cbutton.state == SDL_PRESSED;
      break;
    case SDL_QUIT:
      state_.quit = true;
      break;
    case SDL_WINDOWEVENT:
      if (event.window.event != SDL_WINDOWEVENT_CLOSE) return;
      state_.quit = true;
      break;
    default:
      return;  // nothing changed: publish nothing
  }
  box_.Store(state_);
}

// ---------------------------------------------------------------- InputPump

struct InputPump::Impl {
  interfaces::InputBox& box;
  std::chrono::duration<double> period;
  std::thread thread;
  std::mutex call_mutex;  // one RunOnPumpThread caller at a time
  std::mutex mutex;
  std::condition_variable cv;
  bool stop = false;
  const std::function<void()>* task = nullptr;  // guarded by mutex
  bool task_done = false;
  std::exception_ptr task_error;

  Impl(interfaces::InputBox& b, double rate_hz) : box(b), period(1.0 / rate_hz) {}

  void Run(std::promise<std::string>& started, std::atomic<uint64_t>& polls) {
    // Without a window SDL has no focus to give: let the controller's events
    // through anyway.
    SDL_SetHint(SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS, "1");
    if (SDL_Init(SDL_INIT_GAMECONTROLLER) != 0) {
      started.set_value(SDL_GetError());
      return;
    }
    started.set_value({});
    SdlInput input(box);
    std::unique_lock lock(mutex);
    while (!stop) {
      if (task != nullptr) {
        // Run between polls, so what it does is seen by the poll below.
        try {
          (*task)();
        } catch (...) {
          task_error = std::current_exception();
        }
        task = nullptr;
        task_done = true;
        cv.notify_all();
      }
      lock.unlock();
      SDL_Event event;
      while (SDL_PollEvent(&event) != 0) input.OnEvent(event);
      polls.fetch_add(1, std::memory_order_release);
      lock.lock();
      cv.wait_for(lock, period, [this] { return stop || task != nullptr; });
    }
    lock.unlock();
    input.Release();
    // Leave SDL as found: quit only our subsystem, and SDL itself only when
    // no one else (a view) still uses it.
    SDL_QuitSubSystem(SDL_INIT_GAMECONTROLLER);
    if (SDL_WasInit(0) == 0) SDL_Quit();
  }
};

InputPump::InputPump(interfaces::InputBox& box, double rate_hz) {
  if (!(rate_hz > 0.0)) throw std::invalid_argument("InputPump: rate_hz must be > 0");
  impl_ = std::make_unique<Impl>(box, rate_hz);
  std::promise<std::string> started;
  std::future<std::string> result = started.get_future();
  // The promise moves to the thread: it must outlive its set_value call.
  impl_->thread = std::thread([this, p = std::move(started)]() mutable { impl_->Run(p, polls_); });
  const std::string error = result.get();
  if (!error.empty()) {
    impl_->thread.join();
    throw std::runtime_error("SDL_Init(SDL_INIT_GAMECONTROLLER) failed: " + error);
  }
}

InputPump::~InputPump() { Stop(); }

void InputPump::Stop() {
  if (!impl_ || !impl_->thread.joinable()) return;
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stop = true;
  }
  impl_->cv.notify_all();
  impl_->thread.join();
}

void InputPump::RunOnPumpThread(const std::function<void()>& fn) {
  std::lock_guard call(impl_->call_mutex);
  std::unique_lock lock(impl_->mutex);
  if (impl_->stop || !impl_->thread.joinable()) throw std::logic_error("InputPump: not running");
  impl_->task = &fn;
  impl_->task_done = false;
  impl_->task_error = nullptr;
  impl_->cv.notify_all();
  impl_->cv.wait(lock, [this] { return impl_->task_done; });
  if (impl_->task_error) std::rethrow_exception(impl_->task_error);
}

}  // namespace haptel::view
