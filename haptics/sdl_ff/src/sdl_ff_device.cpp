#include "haptel/sdl_ff/sdl_ff_device.hpp"

#include <SDL2/SDL.h>
#include <pthread.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <future>
#include <thread>
#include <vector>

#include "haptel/config/error.hpp"
#include "haptel/core/clock.hpp"
#include "haptel/core/log.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/sdl_ff/ff_model.hpp"
#include "haptel/sdl_ff/sdl_effects.hpp"

namespace haptel::haptics {

using sdl_ff::Axes;
using sdl_ff::FfSide;
using sdl_ff::kFfAxes;
using sdl_ff::kMaxAxes;

namespace {

constexpr unsigned kEffectKinds = SDL_HAPTIC_SPRING | SDL_HAPTIC_CONSTANT | SDL_HAPTIC_SINE;

/// One joystick as SDL lists it, and what it can play.
struct Joystick {
  int index = -1;
  std::string name;
  bool effects = false;  ///< a spring, a constant force or a sine through SDL's haptic API
  bool rumble = false;
};

/// SDL's joysticks, each opened just long enough to ask what it plays. The
/// joystick subsystem (and the haptic one, when `haptic`) must be up.
std::vector<Joystick> ListJoysticks(bool haptic) {
  std::vector<Joystick> list;
  const int n = SDL_NumJoysticks();
  for (int i = 0; i < n; ++i) {
    Joystick j;
    j.index = i;
    const char* name = SDL_JoystickNameForIndex(i);
    j.name = name != nullptr ? name : "unnamed";
    if (SDL_Joystick* joy = SDL_JoystickOpen(i); joy != nullptr) {
      if (haptic && SDL_JoystickIsHaptic(joy) == 1) {
        if (SDL_Haptic* h = SDL_HapticOpenFromJoystick(joy); h != nullptr) {
          j.effects = (SDL_HapticQuery(h) & kEffectKinds) != 0;
          SDL_HapticClose(h);
        }
      }
      j.rumble = SDL_JoystickHasRumble(joy) == SDL_TRUE;
      SDL_JoystickClose(joy);
    }
    list.push_back(std::move(j));
  }
  return list;
}

std::string Names(const std::vector<Joystick>& list) {
  std::string names;
  for (const Joystick& j : list) {
    names += (names.empty() ? "" : ", ") + std::to_string(j.index) + " '" + j.name + "'";
  }
  return names;
}

/// The joystick `wanted` picks (−1: the first with effects, else with
/// rumble), or a line saying why there is none.
std::string Pick(const std::vector<Joystick>& list, int wanted, Joystick& out) {
  if (list.empty()) {
    return "no joystick is connected (SDL lists none): plug in a force-feedback joystick or "
           "wheel, or a game controller with rumble";
  }
  if (wanted >= 0) {
    if (wanted >= static_cast<int>(list.size())) {
      return "joystick " + std::to_string(wanted) + " is not there: SDL lists " +
             std::to_string(list.size()) + " (" + Names(list) + ")";
    }
    out = list[static_cast<size_t>(wanted)];
    if (!out.effects && !out.rumble) {
      return "joystick " + std::to_string(wanted) + " '" + out.name +
             "' has no force feedback and no rumble";
    }
    return {};
  }
  for (const bool effects : {true, false}) {
    for (const Joystick& j : list) {
      if (effects ? j.effects : j.rumble) {
        out = j;
        return {};
      }
    }
  }
  return "none of the joysticks SDL lists (" + Names(list) + ") has force feedback or rumble";
}

/// Brings up SDL's joystick subsystem (and the haptic one, when it can) for
/// this device, and quits them again: both are reference-counted, so a view
/// that also uses them keeps them. The hints are SDL's defaults the view
/// sets too: Ctrl-C stays the session's, and the axes read without a
/// focused window.
class SdlSubsystems {
 public:
  SdlSubsystems() {
    SDL_SetHint(SDL_HINT_NO_SIGNAL_HANDLERS, "1");
    SDL_SetHint(SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS, "1");
    joystick_ = SDL_InitSubSystem(SDL_INIT_JOYSTICK) == 0;
    if (!joystick_) error_ = SDL_GetError();
    haptic_ = joystick_ && SDL_InitSubSystem(SDL_INIT_HAPTIC) == 0;
  }
  ~SdlSubsystems() {
    if (haptic_) SDL_QuitSubSystem(SDL_INIT_HAPTIC);
    if (joystick_) SDL_QuitSubSystem(SDL_INIT_JOYSTICK);
    if (SDL_WasInit(0) == 0) SDL_Quit();
  }
  SdlSubsystems(const SdlSubsystems&) = delete;
  SdlSubsystems& operator=(const SdlSubsystems&) = delete;
  bool joystick() const { return joystick_; }
  bool haptic() const { return haptic_; }
  const std::string& error() const { return error_; }

 private:
  bool joystick_ = false;
  bool haptic_ = false;
  std::string error_;
};

/// The axes and buttons a device file names that the joystick lacks: the
/// first one's key and what is expected, or "".
std::string MissingInput(const DeviceConfig& config, int axes, int buttons, std::string& key) {
  const SdlFfDeviceConfig& f = config.sdl_ff;
  const auto check_axis = [&](const std::string& at, int axis) {
    if (axis >= axes && key.empty()) key = at;
  };
  constexpr const char* kSides[2] = {"left", "right"};
  const std::array<const SdlFfHandMap*, 2> hands{&f.left, &f.right};
  for (int s = 0; s < 2; ++s) {
    if (!config.sides[s]) continue;
    const std::string hand = std::string("sdl_ff.") + kSides[s] + ".";
    const std::array<std::pair<const char*, const SdlFfAxisMap*>, 3> maps{
        {{"x", &hands[s]->x}, {"y", &hands[s]->y}, {"z", &hands[s]->z}}};
    for (const auto& [c, m] : maps) {
      check_axis(hand + c + ".axis", m->axis);
      check_axis(hand + c + ".reverse_axis", m->reverse_axis);
    }
    check_axis(hand + "rim.axis", hands[s]->rim.axis);
  }
  check_axis("sdl_ff.deadman.axis", f.deadman.axis);
  if (!key.empty()) {
    return "an axis the joystick has (it has " + std::to_string(axes) + ": 0 to " +
           std::to_string(axes - 1) + ")";
  }
  if (f.deadman.button >= buttons) {
    key = "sdl_ff.deadman.button";
    return "a button the joystick has (it has " + std::to_string(buttons) + ": 0 to " +
           std::to_string(buttons - 1) + ")";
  }
  return {};
}

}  // namespace

/// What the servo threads and the I/O thread share, and the thread itself.
struct SdlFfDevice::Io {
  /// The hands as of one poll.
  struct Reading {
    uint64_t poll = 0;  ///< counts polls: a new one is a fresh reading
    std::array<sdl_ff::HandPose, kSides> hands{};
    bool held = false;
  };
  struct StampedForce {
    int64_t t_ns = 0;
    Vec3d force{};
  };
  struct StampedField {
    int64_t stamp_ns = 0;
    ForceField field;
    uint64_t contacts = 0;  ///< the set-point's count of the vehicle's contacts
  };

  DeviceConfig config;
  const SdlFfDeviceConfig& ff;
  double force_limit;
  int64_t fresh_ns;  ///< a set-point or force older than this plays nothing

  // I/O thread → servo threads.
  Seqlock<Reading> reading;
  std::atomic<bool> lost{false};
  std::atomic<bool> held{false};
  // Servo threads → I/O thread, one writer per side.
  std::array<Seqlock<StampedForce>, kSides> forces;
  std::array<Seqlock<StampedField>, kSides> fields;
  // Counted by the I/O thread.
  std::atomic<uint64_t> effects_played{0};
  std::atomic<uint64_t> shakes{0};

  Joystick joystick;
  bool plays =
      false;  ///< through SDL's haptic API (else rumble); set before the thread says it opened
  std::atomic<bool> stop{false};
  std::thread thread;

  explicit Io(const DeviceConfig& c)
      : config(c),
        ff(config.sdl_ff),
        force_limit(std::max(c.safety.wrist_force_limit, 1e-3)),
        fresh_ns(SToNs(c.safety.setpoint_timeout_s + c.safety.fade_s)) {}

  /// The thread: opens, then polls and plays until told to stop or the joystick goes.
  void Run(std::promise<std::string>& opened);

  // Everything below runs on the I/O thread only.
  SDL_Joystick* joy = nullptr;
  SDL_Haptic* haptic = nullptr;
  unsigned supported = 0;
  int ff_axes = 0;
  int spring_id = -1, constant_id = -1, sine_id = -1;
  bool spring_on = false, constant_on = false, wall_rumble = false;
  double rumble_until_s = -1e9;
  sdl_ff::FfPlan last_plan{};

  std::string Open(SdlSubsystems& sdl);
  void Close();
  void Poll(uint64_t poll, Axes& axes);
  void Play(double t_s, const Axes& axes, sdl_ff::ShakeTrigger& shake);
  /// Starts (counted) or updates a haptic effect, or stops it.
  void Drive(int id, const SDL_HapticEffect& effect, bool on, bool& running);
};

std::string SdlFfDevice::Io::Open(SdlSubsystems& sdl) {
  if (!sdl.joystick()) return "SDL cannot start its joystick subsystem: " + sdl.error();
  const std::vector<Joystick> list = ListJoysticks(sdl.haptic());
  if (std::string why = Pick(list, ff.joystick, joystick); !why.empty()) {
    return "key 'sdl_ff.joystick': " + why;
  }
  joy = SDL_JoystickOpen(joystick.index);
  if (joy == nullptr) {
    return "key 'sdl_ff.joystick': SDL cannot open joystick " + std::to_string(joystick.index) +
           " '" + joystick.name + "': " + SDL_GetError();
  }
  std::string key;
  const std::string expected =
      MissingInput(config, SDL_JoystickNumAxes(joy), SDL_JoystickNumButtons(joy), key);
  if (!expected.empty()) {
    return "key '" + key + "': expected " + expected + " (joystick '" + joystick.name + "')";
  }
  if (joystick.effects) {
    haptic = SDL_HapticOpenFromJoystick(joy);
    if (haptic == nullptr) {
      return "key 'sdl_ff.joystick': SDL cannot open the force feedback of '" + joystick.name +
             "': " + SDL_GetError();
    }
    plays = true;
    supported = SDL_HapticQuery(haptic);
    ff_axes = std::clamp(SDL_HapticNumAxes(haptic), 0, kFfAxes);
    // The interface's field is the only centring: the device's own spring off.
    if ((supported & SDL_HAPTIC_AUTOCENTER) != 0) SDL_HapticSetAutocenter(haptic, 0);
    if ((supported & SDL_HAPTIC_GAIN) != 0) SDL_HapticSetGain(haptic, 100);
    SDL_HapticEffect e = sdl_ff::SpringEffect({});
    if ((supported & SDL_HAPTIC_SPRING) != 0) spring_id = SDL_HapticNewEffect(haptic, &e);
    e = sdl_ff::ConstantEffect({});
    if ((supported & SDL_HAPTIC_CONSTANT) != 0) constant_id = SDL_HapticNewEffect(haptic, &e);
    e = sdl_ff::ShakeEffect(ff);
    if ((supported & SDL_HAPTIC_SINE) != 0) sine_id = SDL_HapticNewEffect(haptic, &e);
  }
  return {};
}

void SdlFfDevice::Io::Close() {
  if (haptic != nullptr) {
    SDL_HapticStopAll(haptic);
    for (const int id : {spring_id, constant_id, sine_id}) {
      if (id >= 0) SDL_HapticDestroyEffect(haptic, id);
    }
    SDL_HapticClose(haptic);
    haptic = nullptr;
  }
  if (joy != nullptr) {
    if (wall_rumble || rumble_until_s > 0) SDL_JoystickRumble(joy, 0, 0, 0);
    SDL_JoystickClose(joy);
    joy = nullptr;
  }
}

void SdlFfDevice::Io::Poll(uint64_t poll, Axes& axes) {
  const int n = std::min(SDL_JoystickNumAxes(joy), kMaxAxes);
  for (int i = 0; i < n; ++i)
    axes[static_cast<size_t>(i)] = sdl_ff::AxisFromSdl(SDL_JoystickGetAxis(joy, i));
  uint64_t buttons = 0;
  const int nb = std::min(SDL_JoystickNumButtons(joy), 64);
  for (int b = 0; b < nb; ++b) {
    if (SDL_JoystickGetButton(joy, b) != 0) buttons |= uint64_t{1} << b;
  }
  Reading r;
  r.poll = poll;
  r.hands = {sdl_ff::HandFromAxes(ff.left, axes), sdl_ff::HandFromAxes(ff.right, axes)};
  r.held = sdl_ff::DeadmanHeld(ff.deadman, axes, buttons);
  held.store(r.held, std::memory_order_release);
  reading.Store(r);
}

void SdlFfDevice::Io::Drive(int id, const SDL_HapticEffect& effect, bool on, bool& running) {
  if (id < 0) return;
  if (on) {
    SDL_HapticEffect e = effect;
    SDL_HapticUpdateEffect(haptic, id, &e);
    if (!running && SDL_HapticRunEffect(haptic, id, 1) == 0) {
      running = true;
      effects_played.fetch_add(1, std::memory_order_relaxed);
    }
  } else if (running) {
    SDL_HapticStopEffect(haptic, id);
    running = false;
  }
}

void SdlFfDevice::Io::Play(double t_s, const Axes& axes, sdl_ff::ShakeTrigger& shake) {
  const int64_t now = MonotonicNs();
  std::array<FfSide, kSides> sides{};
  for (int s = 0; s < kSides; ++s) {
    FfSide& side = sides[s];
    side.used = config.sides[s];
    const StampedField field = fields[s].Load();
    const StampedForce force = forces[s].Load();
    side.fresh = side.used && field.stamp_ns != 0 && now - field.stamp_ns <= fresh_ns &&
                 force.t_ns != 0 && now - force.t_ns <= fresh_ns;
    side.field = field.field;
    side.contacts = field.contacts;
    side.force = force.force;
  }
  const bool shake_now = shake.Step(t_s, sides);
  if (haptic != nullptr) {
    const sdl_ff::FfPlan plan =
        sdl_ff::PlanEffects(ff, sides, axes, ff_axes, spring_id >= 0, force_limit);
    bool any_spring = false;
    for (const sdl_ff::SpringAxis& a : plan.spring) any_spring = any_spring || a.active;
    Drive(spring_id, sdl_ff::SpringEffect(plan.spring), any_spring, spring_on);
    double level2 = 0.0;
    for (const double l : plan.constant) level2 += l * l;
    Drive(constant_id, sdl_ff::ConstantEffect(plan.constant), level2 > 1e-6, constant_on);
    if (shake_now && sine_id >= 0 && SDL_HapticRunEffect(haptic, sine_id, 1) == 0) {
      effects_played.fetch_add(1, std::memory_order_relaxed);
      shakes.fetch_add(1, std::memory_order_relaxed);
    }
    last_plan = plan;
    return;
  }
  // Rumble only: the shake, and a wall pressed as long as it is pressed.
  if (shake_now) {
    const Uint16 level = sdl_ff::RumbleLevel(ff.shake_level);
    if (SDL_JoystickRumble(joy, level, level, static_cast<Uint32>(ff.shake_s * 1000.0)) == 0) {
      effects_played.fetch_add(1, std::memory_order_relaxed);
      shakes.fetch_add(1, std::memory_order_relaxed);
      rumble_until_s = t_s + ff.shake_s;
    }
    return;
  }
  if (t_s < rumble_until_s) return;  // the shake plays on
  const sdl_ff::FfPlan plan = sdl_ff::PlanEffects(ff, sides, axes, 0, false, force_limit);
  if (plan.wall_press > 0.0) {
    // Renewed each period, lasting two: it stops by itself if this thread stalls.
    const auto ms = static_cast<Uint32>(std::ceil(2000.0 / ff.effect_hz));
    if (SDL_JoystickRumble(joy, sdl_ff::RumbleLevel(plan.wall_press), 0, ms) == 0 && !wall_rumble) {
      wall_rumble = true;
      effects_played.fetch_add(1, std::memory_order_relaxed);
    }
  } else if (wall_rumble) {
    SDL_JoystickRumble(joy, 0, 0, 0);
    wall_rumble = false;
  }
}

void SdlFfDevice::Io::Run(std::promise<std::string>& opened) {
  pthread_setname_np(pthread_self(), "sdl-ff");
  SdlSubsystems sdl;
  if (std::string error = Open(sdl); !error.empty()) {
    Close();
    opened.set_value(error);
    return;
  }
  Axes axes{};
  uint64_t poll = 1;
  SDL_JoystickUpdate();
  Poll(poll, axes);
  opened.set_value({});

  sdl_ff::ShakeTrigger shake(ff);
  const int64_t period_ns = SToNs(1.0 / ff.poll_hz);
  const int64_t effect_ns = SToNs(1.0 / ff.effect_hz);
  const int64_t t0 = MonotonicNs();
  int64_t next = t0, next_effect = t0;
  while (!stop.load(std::memory_order_acquire)) {
    next += period_ns;
    SleepUntilNs(next);
    const int64_t now = MonotonicNs();
    if (next < now - period_ns) next = now;  // fell behind: do not race to catch up
    SDL_JoystickUpdate();
    if (SDL_JoystickGetAttached(joy) != SDL_TRUE) {
      lost.store(true, std::memory_order_release);
      held.store(false, std::memory_order_release);
      log::Error("device '" + config.name + "': joystick '" + joystick.name +
                 "' was unplugged: the device is lost, forces zeroed and the vehicle held");
      break;
    }
    Poll(++poll, axes);
    if (now >= next_effect) {
      next_effect += effect_ns;
      if (next_effect < now) next_effect = now + effect_ns;
      Play(NsToS(now - t0), axes, shake);
    }
  }
  Close();
  // Lost: wait to be stopped, so that a destructor joining this thread finds it.
  while (!stop.load(std::memory_order_acquire)) SleepUntilNs(MonotonicNs() + SToNs(0.02));
}

SdlFfDevice::SdlFfDevice(const DeviceConfig& config) : io_(std::make_unique<Io>(config)) {
  description_.name = config.name;
  description_.has_side = config.sides;
  description_.wrist_force_limit = config.safety.wrist_force_limit;
  description_.finger_force_limit = config.safety.finger_force_limit;
  description_.has_glove = config.has_glove;
  description_.has_grasp = config.has_grasp;
  std::promise<std::string> opened;
  std::future<std::string> result = opened.get_future();
  io_->thread = std::thread([io = io_.get(), p = std::move(opened)]() mutable { io->Run(p); });
  const std::string error = result.get();
  if (!error.empty()) {
    io_->stop.store(true);
    io_->thread.join();
    throw ConfigError(config.file.string() + ": " + error);
  }
  const char* kind = io_->plays ? "force feedback" : "rumble only";
  log::Info("device '" + config.name + "': joystick '" + io_->joystick.name + "' (" + kind + ")");
}

SdlFfDevice::~SdlFfDevice() {
  io_->stop.store(true, std::memory_order_release);
  if (io_->thread.joinable()) io_->thread.join();
}

DeviceStatus SdlFfDevice::ReadWrist(Side side, int64_t now_ns, WristRaw& out) {
  if (io_->lost.load(std::memory_order_acquire)) return DeviceStatus::kLost;
  Io::Reading r;
  if (!io_->reading.TryLoad(r, 4) || r.poll == seen_[Index(side)]) return DeviceStatus::kNoData;
  seen_[Index(side)] = r.poll;
  out.t_ns = now_ns;
  out.position = r.hands[Index(side)].position;
  out.orientation = r.hands[Index(side)].orientation;
  return DeviceStatus::kOk;
}

DeviceStatus SdlFfDevice::ReadGlove(Side side, int64_t now_ns, GloveRaw& out) {
  (void)side;
  if (io_->lost.load(std::memory_order_acquire)) return DeviceStatus::kLost;
  out.t_ns = now_ns;
  out.sensors =
      sdl_ff::GlovePosture(io_->ff.grasp_flexion, io_->held.load(std::memory_order_acquire));
  out.grasp = {};
  return DeviceStatus::kOk;
}

DeviceStatus SdlFfDevice::WriteWristForce(Side side, const Vec3d& command) {
  if (io_->lost.load(std::memory_order_acquire)) return DeviceStatus::kLost;
  io_->forces[Index(side)].Store({MonotonicNs(), command});
  return DeviceStatus::kOk;
}

DeviceStatus SdlFfDevice::WriteFingerForces(Side side,
                                            const std::array<double, kFingers>& command) {
  (void)side;
  (void)command;  // no finger forces on a joystick
  return io_->lost.load(std::memory_order_acquire) ? DeviceStatus::kLost : DeviceStatus::kOk;
}

HandPresence SdlFfDevice::Presence(Side side) {
  (void)side;  // one deadman holds both hands
  return io_->held.load(std::memory_order_acquire) ? HandPresence::kHeld : HandPresence::kReleased;
}

void SdlFfDevice::SetpointHint(Side side, const ForceSetpoint& setpoint) {
  io_->fields[Index(side)].Store({setpoint.stamp_ns, setpoint.field, setpoint.contacts});
}

DeviceUseReport SdlFfDevice::UseReport() const {
  DeviceUseReport report;
  report.ff_effects_played = io_->effects_played.load(std::memory_order_relaxed);
  report.shakes = io_->shakes.load(std::memory_order_relaxed);
  return report;
}

std::string SdlFfDevice::UnpluggedLine() const {
  if (!io_->lost.load(std::memory_order_acquire)) return {};
  return "joystick '" + io_->joystick.name + "' was unplugged";
}

const std::string& SdlFfDevice::joystick_name() const { return io_->joystick.name; }
bool SdlFfDevice::plays_effects() const { return io_->plays; }
bool SdlFfDevice::rumbles() const { return !io_->plays; }

std::string SdlFfUnavailable(const DeviceConfig& config) {
  SdlSubsystems sdl;
  if (!sdl.joystick()) return "SDL cannot start its joystick subsystem: " + sdl.error();
  Joystick picked;
  return Pick(ListJoysticks(sdl.haptic()), config.sdl_ff.joystick, picked);
}

}  // namespace haptel::haptics
