#pragma once
/// @file SDL's virtual joystick as a test's controller: axes and buttons set
/// from the test, the rumble it is asked for recorded. SDL_VIDEODRIVER is
/// not needed: only the joystick subsystem is brought up.
#include <SDL2/SDL.h>

#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <string>

namespace haptel::test {

class VirtualJoystick {
 public:
  static constexpr const char* kName = "Haptel test stick";

  /// Holds SDL's joystick subsystem up for the test (reference-counted).
  struct Subsystem {
    Subsystem() {
      SDL_SetHint(SDL_HINT_NO_SIGNAL_HANDLERS, "1");
      if (SDL_InitSubSystem(SDL_INIT_JOYSTICK) != 0)
        throw std::runtime_error(std::string("SDL joystick subsystem: ") + SDL_GetError());
    }
    ~Subsystem() { SDL_QuitSubSystem(SDL_INIT_JOYSTICK); }
    Subsystem(const Subsystem&) = delete;
    Subsystem& operator=(const Subsystem&) = delete;
  };

  /// Four axes (a stick, or a wheel and two pedals) and eight buttons, with a
  /// Rumble callback when `rumble`.
  explicit VirtualJoystick(bool rumble) {
    SDL_VirtualJoystickDesc desc;
    SDL_zero(desc);
    desc.version = SDL_VIRTUAL_JOYSTICK_DESC_VERSION;
    desc.type = SDL_JOYSTICK_TYPE_UNKNOWN;
    desc.naxes = 4;
    desc.nbuttons = 8;
    desc.name = kName;
    desc.userdata = this;
    if (rumble) desc.Rumble = &VirtualJoystick::OnRumble;
    index_ = SDL_JoystickAttachVirtualEx(&desc);
    if (index_ < 0) throw std::runtime_error(std::string("virtual joystick: ") + SDL_GetError());
    joystick_ = SDL_JoystickOpen(index_);
    if (joystick_ == nullptr) throw std::runtime_error(std::string("open: ") + SDL_GetError());
  }
  ~VirtualJoystick() { Detach(); }
  VirtualJoystick(const VirtualJoystick&) = delete;
  VirtualJoystick& operator=(const VirtualJoystick&) = delete;

  /// Applied at the next SDL_JoystickUpdate (the device's thread calls it).
  void SetAxis(int axis, int16_t value) { SDL_JoystickSetVirtualAxis(joystick_, axis, value); }
  void SetButton(int button, bool down) {
    SDL_JoystickSetVirtualButton(joystick_, button, down ? SDL_PRESSED : SDL_RELEASED);
  }
  /// Unplugged: SDL marks every opened handle detached.
  void Detach() {
    if (joystick_ == nullptr) return;
    SDL_JoystickClose(joystick_);
    joystick_ = nullptr;
    // Its index may have moved if another was detached: find it by name.
    for (int i = SDL_NumJoysticks() - 1; i >= 0; --i) {
      if (SDL_JoystickIsVirtual(i) && std::string(SDL_JoystickNameForIndex(i)) == kName) {
        SDL_JoystickDetachVirtual(i);
        break;
      }
    }
  }

  /// Still plugged in, as SDL sees it.
  bool attached() const {
    return joystick_ != nullptr && SDL_JoystickGetAttached(joystick_) == SDL_TRUE;
  }
  int rumbles() const { return rumbles_.load(); }
  int last_low() const { return last_low_.load(); }
  int last_high() const { return last_high_.load(); }
  int strongest_low() const { return strongest_low_.load(); }

 private:
  static int SDLCALL OnRumble(void* self, Uint16 low, Uint16 high) {
    auto& j = *static_cast<VirtualJoystick*>(self);
    if (low > 0 || high > 0) j.rumbles_.fetch_add(1);
    j.last_low_.store(low);
    j.last_high_.store(high);
    int was = j.strongest_low_.load();
    while (low > was && !j.strongest_low_.compare_exchange_weak(was, low)) {
    }
    return 0;
  }

  Subsystem sdl_;
  int index_ = -1;
  SDL_Joystick* joystick_ = nullptr;
  std::atomic<int> rumbles_{0};
  std::atomic<int> last_low_{0};
  std::atomic<int> last_high_{0};
  std::atomic<int> strongest_low_{0};
};

}  // namespace haptel::test
