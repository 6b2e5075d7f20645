// SdlInput from hand-built SDL events: no SDL_Init, no display, no device.
#include <catch2/catch.hpp>

#include "alloc_counter.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/haptics/pointer.hpp"
#include "haptel/view/sdl_input.hpp"

using namespace haptel;
using namespace haptel::interfaces;
using haptel::view::SdlInput;

namespace {
SDL_Event Key(Uint32 type, SDL_Scancode code, Uint8 repeat = 0) {
  SDL_Event e{};
  e.type = type;
  e.key.type = type;
  e.key.state = type == SDL_KEYDOWN ? SDL_PRESSED : SDL_RELEASED;
  e.key.repeat = repeat;
  e.key.keysym.scancode = code;
  return e;
}
SDL_Event Down(SDL_Scancode code, Uint8 repeat = 0) { return Key(SDL_KEYDOWN, code, repeat); }
SDL_Event Up(SDL_Scancode code) { return Key(SDL_KEYUP, code); }
}  // namespace

TEST_CASE("sdl input: arrows and W/A/S/D set held flags and count presses", "[sdl_input]") {
  InputBox box;
  SdlInput input(box);
  input.OnEvent(Down(SDL_SCANCODE_UP));
  CHECK(box.Load().key_up);
  CHECK(box.Load().presses_up == 1);
  // Auto-repeat key-downs are not presses.
  input.OnEvent(Down(SDL_SCANCODE_UP, 1));
  input.OnEvent(Down(SDL_SCANCODE_UP, 1));
  CHECK(box.Load().presses_up == 1);
  // W is up too; up stays held until both are released.
  input.OnEvent(Down(SDL_SCANCODE_W));
  CHECK(box.Load().presses_up == 2);
  input.OnEvent(Up(SDL_SCANCODE_UP));
  CHECK(box.Load().key_up);
  input.OnEvent(Up(SDL_SCANCODE_W));
  CHECK_FALSE(box.Load().key_up);

  input.OnEvent(Down(SDL_SCANCODE_S));
  input.OnEvent(Down(SDL_SCANCODE_A));
  input.OnEvent(Down(SDL_SCANCODE_RIGHT));
  const InputState s = box.Load();
  CHECK(s.key_down);
  CHECK(s.key_left);
  CHECK(s.key_right);
  CHECK(s.presses_down == 1);
  CHECK(s.presses_left == 1);
  CHECK(s.presses_right == 1);
  CHECK_FALSE(s.key_stop);
}

TEST_CASE("sdl input: each physical key is also seen on its own (the blimp's keys)",
          "[sdl_input]") {
  using haptel::interfaces::Key;
  const auto held = [](const InputState& s, Key k) { return s.keys_held[static_cast<size_t>(k)]; };
  const auto presses = [](const InputState& s, Key k) {
    return s.key_presses[static_cast<size_t>(k)];
  };
  InputBox box;
  SdlInput input(box);
  input.OnEvent(Down(SDL_SCANCODE_W));
  input.OnEvent(Down(SDL_SCANCODE_W, 1));  // auto-repeat: not a press
  input.OnEvent(Down(SDL_SCANCODE_PAGEUP));
  InputState s = box.Load();
  CHECK(held(s, Key::kW));
  CHECK(presses(s, Key::kW) == 1);
  CHECK_FALSE(held(s, Key::kArrowUp));  // W is not the up arrow here,
  CHECK(presses(s, Key::kArrowUp) == 0);
  CHECK(s.key_up);  // though the robot's keyboard reads both as up
  CHECK(held(s, Key::kPageUp));
  CHECK(presses(s, Key::kPageUp) == 1);
  input.OnEvent(Up(SDL_SCANCODE_W));
  input.OnEvent(Down(SDL_SCANCODE_UP));
  input.OnEvent(Up(SDL_SCANCODE_PAGEUP));
  input.OnEvent(Down(SDL_SCANCODE_PAGEDOWN));
  s = box.Load();
  CHECK_FALSE(held(s, Key::kW));
  CHECK(held(s, Key::kArrowUp));
  CHECK(presses(s, Key::kArrowUp) == 1);
  CHECK_FALSE(held(s, Key::kPageUp));
  CHECK(presses(s, Key::kPageDown) == 1);
}

TEST_CASE("sdl input: a press shorter than a session tick is still counted", "[sdl_input]") {
  InputBox box;
  SdlInput input(box);
  // Between two reads of the box the key went down and up again.
  const InputState before = box.Load();
  input.OnEvent(Down(SDL_SCANCODE_DOWN));
  input.OnEvent(Up(SDL_SCANCODE_DOWN));
  input.OnEvent(Down(SDL_SCANCODE_SPACE));
  input.OnEvent(Up(SDL_SCANCODE_SPACE));
  const InputState after = box.Load();
  CHECK_FALSE(after.key_down);
  CHECK(after.presses_down == before.presses_down + 1);
  CHECK_FALSE(after.key_stop);
  CHECK(after.presses_stop == before.presses_stop + 1);
}

TEST_CASE("sdl input: F1..F6 request interfaces 0..5, one request per press", "[sdl_input]") {
  InputBox box;
  SdlInput input(box);
  CHECK(box.Load().interface_request == -1);
  input.OnEvent(Down(SDL_SCANCODE_F3));
  CHECK(box.Load().interface_request == 2);
  CHECK(box.Load().interface_requests == 1);
  input.OnEvent(Down(SDL_SCANCODE_F3, 1));  // held: no new request
  CHECK(box.Load().interface_requests == 1);
  input.OnEvent(Up(SDL_SCANCODE_F3));
  input.OnEvent(Down(SDL_SCANCODE_F1));
  CHECK(box.Load().interface_request == 0);
  input.OnEvent(Down(SDL_SCANCODE_F6));
  CHECK(box.Load().interface_request == 5);
  CHECK(box.Load().interface_requests == 3);
  input.OnEvent(Down(SDL_SCANCODE_F7));  // not an interface key
  CHECK(box.Load().interface_request == 5);
  CHECK(box.Load().interface_requests == 3);
}

TEST_CASE(
    "sdl input: Tab asks a fleet for the next vehicle, 1..9 for that one, one request per press",
    "[sdl_input]") {
  InputBox box;
  SdlInput input(box);
  CHECK(box.Load().vehicle_requests == 0);
  input.OnEvent(Down(SDL_SCANCODE_TAB));
  CHECK(box.Load().vehicle_request == interfaces::kNextVehicle);
  CHECK(box.Load().vehicle_requests == 1);
  input.OnEvent(Down(SDL_SCANCODE_TAB, 1));  // held: no new request
  CHECK(box.Load().vehicle_requests == 1);
  input.OnEvent(Up(SDL_SCANCODE_TAB));
  input.OnEvent(Down(SDL_SCANCODE_3));
  CHECK(box.Load().vehicle_request == 2);
  input.OnEvent(Down(SDL_SCANCODE_9));
  CHECK(box.Load().vehicle_request == 8);
  CHECK(box.Load().vehicle_requests == 3);
  input.OnEvent(Down(SDL_SCANCODE_0));  // not a vehicle key
  CHECK(box.Load().vehicle_requests == 3);
  CHECK(box.Load().interface_requests == 0);  // nor an interface's
}

TEST_CASE("sdl input: closing the window, SDL_QUIT or Escape asks to quit", "[sdl_input]") {
  InputBox box;
  SdlInput input(box);
  SDL_Event e{};
  e.type = SDL_WINDOWEVENT;
  e.window.event = SDL_WINDOWEVENT_RESIZED;
  input.OnEvent(e);
  CHECK_FALSE(box.Load().quit);
  SECTION("window close") {
    e.window.event = SDL_WINDOWEVENT_CLOSE;
    input.OnEvent(e);
    CHECK(box.Load().quit);
  }
  SECTION("SDL_QUIT") {
    SDL_Event q{};
    q.type = SDL_QUIT;
    input.OnEvent(q);
    CHECK(box.Load().quit);
  }
  SECTION("Escape") {
    input.OnEvent(Down(SDL_SCANCODE_ESCAPE));
    CHECK(box.Load().quit);
  }
}

TEST_CASE("sdl input: controller events of no open controller are ignored", "[sdl_input]") {
  InputBox box;
  SdlInput input(box);
  SDL_Event e{};
  e.type = SDL_CONTROLLERAXISMOTION;
  e.caxis.which = 0;
  e.caxis.axis = SDL_CONTROLLER_AXIS_LEFTY;
  e.caxis.value = -32768;
  input.OnEvent(e);
  SDL_Event r{};
  r.type = SDL_CONTROLLERDEVICEREMOVED;
  r.cdevice.which = 0;
  input.OnEvent(r);
  const InputState s = box.Load();
  CHECK(s.pad_axes[static_cast<int>(PadAxis::kLeftY)] == 0.0);
  CHECK_FALSE(s.pad_connected);
  CHECK(s.pad_disconnects == 0);
}

TEST_CASE("sdl input: axis values are scaled to [-1, 1], triggers to [0, 1]", "[sdl_input]") {
  CHECK(SdlInput::AxisValue(SDL_CONTROLLER_AXIS_LEFTX, 32767) == 1.0);
  CHECK(SdlInput::AxisValue(SDL_CONTROLLER_AXIS_LEFTX, -32768) == -1.0);
  CHECK(SdlInput::AxisValue(SDL_CONTROLLER_AXIS_LEFTY, 0) == 0.0);
  CHECK(SdlInput::AxisValue(SDL_CONTROLLER_AXIS_RIGHTY, 16384) == Approx(0.5).margin(1e-4));
  CHECK(SdlInput::AxisValue(SDL_CONTROLLER_AXIS_TRIGGERLEFT, 32767) == 1.0);
  CHECK(SdlInput::AxisValue(SDL_CONTROLLER_AXIS_TRIGGERRIGHT, 0) == 0.0);
  CHECK(SdlInput::AxisValue(SDL_CONTROLLER_AXIS_TRIGGERRIGHT, -100) == 0.0);
}

TEST_CASE("sdl input: a new sink keeps the counters and drops held keys", "[sdl_input]") {
  InputBox box;
  {
    SdlInput first(box);
    first.OnEvent(Down(SDL_SCANCODE_UP));
  }
  SdlInput second(box);
  second.OnEvent(Down(SDL_SCANCODE_UP));
  CHECK(box.Load().presses_up == 2);
}

namespace {
SDL_Event Motion(int xrel, int yrel, Uint32 buttons) {
  SDL_Event e{};
  e.type = SDL_MOUSEMOTION;
  e.motion.type = SDL_MOUSEMOTION;
  e.motion.state = buttons;
  e.motion.xrel = xrel;
  e.motion.yrel = yrel;
  return e;
}
}  // namespace

TEST_CASE(
    "sdl input: dragging the mouse with the right button turns the head, within the camera's "
    "range; Home looks ahead",
    "[sdl_input]") {
  InputBox box;
  haptel::haptics::PointerBox pointer;
  SdlInput input(box, pointer);
  // The pointer passing over the window without a button held turns nothing,
  // nor does a drag with the left button (it grasps: the mouse device).
  input.OnEvent(Motion(200, 50, 0));
  input.OnEvent(Motion(200, 50, SDL_BUTTON_LMASK));
  CHECK(box.Load().head_pan == 0.0);
  CHECK(box.Load().head_tilt == 0.0);
  // Dragging right looks right (pan is positive left), dragging up looks up.
  input.OnEvent(Motion(100, 0, SDL_BUTTON_RMASK));
  CHECK(box.Load().head_pan == Approx(-100 * SdlInput::kHeadRadPerPixel));
  input.OnEvent(Motion(-40, -30, SDL_BUTTON_RMASK | SDL_BUTTON_LMASK));
  CHECK(box.Load().head_pan == Approx(-60 * SdlInput::kHeadRadPerPixel));
  CHECK(box.Load().head_tilt == Approx(30 * SdlInput::kHeadRadPerPixel));
  // 300 px is a quarter turn; far past the camera's range stops at its end.
  input.OnEvent(Motion(-360, 0, SDL_BUTTON_RMASK));
  CHECK(box.Load().head_pan == Approx(kBlimpCameraPanMax).margin(1e-3));
  input.OnEvent(Motion(-5000, 5000, SDL_BUTTON_RMASK));
  CHECK(box.Load().head_pan == Approx(kBlimpCameraPanMax));
  CHECK(box.Load().head_tilt == Approx(-kBlimpCameraTiltMax));
  // Coming back needs only the way back, not the overshoot.
  input.OnEvent(Motion(300, 0, SDL_BUTTON_RMASK));
  CHECK(box.Load().head_pan == Approx(0.0).margin(1e-3));
  input.OnEvent(Down(SDL_SCANCODE_HOME));
  CHECK(box.Load().head_pan == 0.0);
  CHECK(box.Load().head_tilt == 0.0);
}

TEST_CASE("sdl input: events allocate nothing", "[sdl_input][alloc]") {
  InputBox box;
  SdlInput input(box);
  const SDL_Event events[] = {
      Down(SDL_SCANCODE_UP),           Up(SDL_SCANCODE_UP),     Down(SDL_SCANCODE_A, 0),
      Down(SDL_SCANCODE_F2),           Up(SDL_SCANCODE_SPACE),  Down(SDL_SCANCODE_SPACE),
      Down(SDL_SCANCODE_PAGEUP),       Up(SDL_SCANCODE_PAGEUP), Motion(3, -2, SDL_BUTTON_RMASK),
      Motion(3, -2, SDL_BUTTON_LMASK), Down(SDL_SCANCODE_Q),    Up(SDL_SCANCODE_Q)};
  const uint64_t before = haptel::test::ThreadAllocations();
  for (int i = 0; i < 1000; ++i) {
    for (const SDL_Event& e : events) input.OnEvent(e);
  }
  CHECK(haptel::test::ThreadAllocations() == before);
}

namespace {
SDL_Event MotionAt(int x, int y, Uint32 buttons) {
  SDL_Event e = Motion(0, 0, buttons);
  e.motion.x = x;
  e.motion.y = y;
  return e;
}
SDL_Event Button(Uint32 type, Uint8 button, int x, int y) {
  SDL_Event e{};
  e.type = type;
  e.button.type = type;
  e.button.button = button;
  e.button.state = type == SDL_MOUSEBUTTONDOWN ? SDL_PRESSED : SDL_RELEASED;
  e.button.x = x;
  e.button.y = y;
  return e;
}
SDL_Event Window(Uint8 what, int data1 = 0, int data2 = 0) {
  SDL_Event e{};
  e.type = SDL_WINDOWEVENT;
  e.window.type = SDL_WINDOWEVENT;
  e.window.event = what;
  e.window.data1 = data1;
  e.window.data2 = data2;
  return e;
}
SDL_Event Wheel(int notches, bool flipped = false) {
  SDL_Event e{};
  e.type = SDL_MOUSEWHEEL;
  e.wheel.type = SDL_MOUSEWHEEL;
  e.wheel.y = notches;
  e.wheel.direction = flipped ? SDL_MOUSEWHEEL_FLIPPED : SDL_MOUSEWHEEL_NORMAL;
  return e;
}
}  // namespace

TEST_CASE(
    "sdl input: the pointer's window, place, button, wheel and the key hand's keys are stored "
    "for the mouse device",
    "[sdl_input]") {
  using haptel::haptics::KeyHandKey;
  using haptel::haptics::PointerState;
  InputBox box;
  haptel::haptics::PointerBox pointer;
  SdlInput input(box, pointer);
  const auto key = [](const PointerState& p, KeyHandKey k) {
    return p.key_hand[static_cast<size_t>(k)];
  };
  CHECK_FALSE(pointer.Load().window_open);
  input.OnWindowOpened(nullptr, 1024, 576);
  PointerState p = pointer.Load();
  CHECK(p.window_open);
  CHECK(p.width_px == 1024);
  CHECK(p.height_px == 576);
  const uint64_t events = p.events;
  // Enter, move (no button), press the left button, drag, release.
  input.OnEvent(Window(SDL_WINDOWEVENT_ENTER));
  CHECK(pointer.Load().in_window);
  input.OnEvent(MotionAt(300, 200, 0));
  CHECK(pointer.Load().x_px == 300);
  CHECK(pointer.Load().y_px == 200);
  input.OnEvent(Button(SDL_MOUSEBUTTONDOWN, SDL_BUTTON_LEFT, 310, 205));
  p = pointer.Load();
  CHECK(p.grasp_button);
  CHECK(p.x_px == 310);
  input.OnEvent(MotionAt(400, 100, SDL_BUTTON_LMASK));
  CHECK(pointer.Load().x_px == 400);
  CHECK(pointer.Load().grasp_button);
  CHECK(box.Load().head_pan == 0.0);  // the left button grasps; it does not look
  // A drag out of the window is reported from outside it: not in the window.
  input.OnEvent(MotionAt(1100, 100, SDL_BUTTON_LMASK));
  CHECK_FALSE(pointer.Load().in_window);
  input.OnEvent(MotionAt(500, 100, SDL_BUTTON_LMASK));
  CHECK(pointer.Load().in_window);
  input.OnEvent(Button(SDL_MOUSEBUTTONUP, SDL_BUTTON_LEFT, 500, 100));
  CHECK_FALSE(pointer.Load().grasp_button);
  // The right button is not the grasp.
  input.OnEvent(Button(SDL_MOUSEBUTTONDOWN, SDL_BUTTON_RIGHT, 500, 100));
  CHECK_FALSE(pointer.Load().grasp_button);
  // The wheel: + away from the user, whichever way the system turns it.
  input.OnEvent(Wheel(2));
  input.OnEvent(Wheel(1, true));
  CHECK(pointer.Load().wheel_notches == 1);
  // A new size; leaving.
  input.OnEvent(Window(SDL_WINDOWEVENT_SIZE_CHANGED, 800, 600));
  CHECK(pointer.Load().width_px == 800);
  CHECK(pointer.Load().height_px == 600);
  input.OnEvent(Window(SDL_WINDOWEVENT_LEAVE));
  CHECK_FALSE(pointer.Load().in_window);
  // The key hand: W and the up arrow are +x (held until both are up), A +y, E −z.
  input.OnEvent(Down(SDL_SCANCODE_W));
  input.OnEvent(Down(SDL_SCANCODE_UP));
  input.OnEvent(Up(SDL_SCANCODE_W));
  CHECK(key(pointer.Load(), KeyHandKey::kPlusX));
  input.OnEvent(Up(SDL_SCANCODE_UP));
  CHECK_FALSE(key(pointer.Load(), KeyHandKey::kPlusX));
  input.OnEvent(Down(SDL_SCANCODE_A));
  input.OnEvent(Down(SDL_SCANCODE_E));
  input.OnEvent(Down(SDL_SCANCODE_RIGHT));
  p = pointer.Load();
  CHECK(key(p, KeyHandKey::kPlusY));
  CHECK(key(p, KeyHandKey::kMinusY));
  CHECK(key(p, KeyHandKey::kMinusZ));
  CHECK_FALSE(key(p, KeyHandKey::kPlusZ));
  CHECK_FALSE(key(p, KeyHandKey::kMinusX));
  input.OnEvent(Down(SDL_SCANCODE_Q));
  CHECK(key(pointer.Load(), KeyHandKey::kPlusZ));
  CHECK(box.Load().key_left);  // the keys still drive the key interfaces too
  CHECK(pointer.Load().events > events);
  // The window closes: nothing is known of the pointer any more.
  input.OnWindowClosed();
  CHECK_FALSE(pointer.Load().window_open);
  CHECK_FALSE(pointer.Load().in_window);
  // The next window (a study's next trial, in this process): its hand
  // starts at its rest height, not the last window's notches.
  REQUIRE(pointer.Load().wheel_notches == 1);
  SdlInput next(box, pointer);
  next.OnWindowOpened(nullptr, 1024, 576);
  CHECK(pointer.Load().wheel_notches == 0);
}

TEST_CASE(
    "sdl input: a window closed with the key hand's keys held lets them go (the next trial's "
    "mouse device does not start with them held)",
    "[sdl_input]") {
  InputBox box;
  haptel::haptics::PointerBox pointer;
  SdlInput input(box, pointer);
  input.OnWindowOpened(nullptr, 1024, 576);
  input.OnEvent(Down(SDL_SCANCODE_A));
  input.OnEvent(Down(SDL_SCANCODE_Q));
  const auto any_held = [](const haptel::haptics::PointerState& p) {
    for (const bool held : p.key_hand)
      if (held) return true;
    return false;
  };
  REQUIRE(any_held(pointer.Load()));
  // The trial ends with A and Q down: their releases come to no window.
  input.OnWindowClosed();
  CHECK_FALSE(any_held(pointer.Load()));
  // What the next trial's mouse device reads until its window opens: its
  // key hand stays at rest (a held +y walked it 0.15 m/s off).
  MouseDeviceConfig mouse;
  const haptel::haptics::Vec3d rest{mouse.key_hand_rest[0], mouse.key_hand_rest[1],
                                    mouse.key_hand_rest[2]};
  CHECK(haptel::haptics::StepKeyHand(rest, pointer.Load(), mouse, 3.0) == rest);
  // Q pressed again in the next window is a new press, released as ever.
  SdlInput next(box, pointer);
  next.OnWindowOpened(nullptr, 1024, 576);
  next.OnEvent(Down(SDL_SCANCODE_Q));
  CHECK(any_held(pointer.Load()));
  next.OnEvent(Up(SDL_SCANCODE_Q));
  CHECK_FALSE(any_held(pointer.Load()));
}

TEST_CASE("sdl input: F turns the force arrows on and off", "[sdl_input]") {
  InputBox box;
  haptel::haptics::PointerBox pointer;
  SdlInput input(box, pointer);
  CHECK_FALSE(input.force_arrows());
  input.OnEvent(Down(SDL_SCANCODE_F));
  CHECK(input.force_arrows());
  input.OnEvent(Down(SDL_SCANCODE_F, 1));  // auto-repeat: no toggle
  input.OnEvent(Up(SDL_SCANCODE_F));
  CHECK(input.force_arrows());
  input.OnEvent(Down(SDL_SCANCODE_F));
  CHECK_FALSE(input.force_arrows());
}
