#include "haptel/interfaces/blimp_manual.hpp"

#include <algorithm>
#include <cmath>

#include "haptel/config/error.hpp"
#include "haptel/interfaces/catalog.hpp"
#include "haptel/interfaces/gamepad.hpp"

namespace haptel::interfaces {

namespace {

bool Held(const InputState& s, Key k) { return s.keys_held[static_cast<size_t>(k)]; }
uint32_t Presses(const InputState& s, Key k) { return s.key_presses[static_cast<size_t>(k)]; }
double Axis(const InputState& s, PadAxis a) { return s.pad_axes[static_cast<size_t>(a)]; }

}  // namespace

BlimpManualInterface::BlimpManualInterface(const BlimpManualConfig& config,
                                           const InputState& at_start)
    : config_(Validated(config)),
      power_(0, config_.power_steps, config_.repeat_s, false),
      helix_(-config_.helix_steps, config_.helix_steps, config_.repeat_s, false),
      elevator_(-config_.elevator_steps, config_.elevator_steps, config_.repeat_s, false),
      seen_stop_(at_start.presses_stop),
      disconnects_at_start_(at_start.pad_disconnects) {
  power_.Skip(Presses(at_start, Key::kW), Presses(at_start, Key::kS));
  helix_.Skip(Presses(at_start, Key::kArrowUp), Presses(at_start, Key::kArrowDown));
  elevator_.Skip(Presses(at_start, Key::kPageUp), Presses(at_start, Key::kPageDown));
}

BlimpCommand BlimpManualInterface::Keys(double t_s, const InputState& s) {
  power_.Step(t_s, Held(s, Key::kW), Held(s, Key::kS), Presses(s, Key::kW), Presses(s, Key::kS));
  helix_.Step(t_s, Held(s, Key::kArrowUp), Held(s, Key::kArrowDown), Presses(s, Key::kArrowUp),
              Presses(s, Key::kArrowDown));
  elevator_.Step(t_s, Held(s, Key::kPageUp), Held(s, Key::kPageDown), Presses(s, Key::kPageUp),
                 Presses(s, Key::kPageDown));

  // The rudder swings while a key is held and comes back when let go, at a
  // rate of its own: a tap is a nudge, a hold a full turn.
  const double dt = started_ ? std::clamp(t_s - last_t_s_, 0.0, 0.5) : 0.0;
  const bool left = Held(s, Key::kA) || Held(s, Key::kArrowLeft);
  const bool right = Held(s, Key::kD) || Held(s, Key::kArrowRight);
  const double target = left == right ? 0.0 : (left ? 1.0 : -1.0);
  const double step = config_.rudder_rate * dt;
  swing_ = target > swing_ ? std::min(target, swing_ + step) : std::max(target, swing_ - step);

  if (s.presses_stop != seen_stop_ || s.key_stop) {
    power_.set_level(0);
    helix_.set_level(0);
    elevator_.set_level(0);
    swing_ = 0.0;
  }
  seen_stop_ = s.presses_stop;

  BlimpCommand c;
  c.power = static_cast<double>(power_.level()) / config_.power_steps;
  c.helix = static_cast<double>(helix_.level()) / config_.helix_steps;
  c.elevator = static_cast<double>(elevator_.level()) / config_.elevator_steps;
  // As the gesture cockpit: the tail rotor turns only with the power off.
  if (power_.level() == 0) {
    c.tail_rotor = swing_;
  } else {
    c.rudder = swing_;
  }
  return c;
}

BlimpCommand BlimpManualInterface::Pad(const InputState& s) {
  if (s.pad_disconnects != disconnects_at_start_) lost_ = true;
  pad_connected_ = s.pad_connected;
  if (lost_ || !s.pad_connected) return {};
  const auto left =
      RadialDeadZone(Axis(s, PadAxis::kLeftX), Axis(s, PadAxis::kLeftY), config_.dead_zone);
  const auto right =
      RadialDeadZone(Axis(s, PadAxis::kRightX), Axis(s, PadAxis::kRightY), config_.dead_zone);
  BlimpCommand c;
  // SDL's sticks: x + right, y + down (pulled back).
  c.power = std::max(0.0, -left[1]);
  if (c.power == 0.0) c.tail_rotor = -left[0];
  c.rudder = -right[0];
  c.elevator = right[1];  // pulled back: nose up, as a stick
  c.helix = TriggerDeadZone(Axis(s, PadAxis::kTriggerRight), config_.trigger_dead_zone) -
            TriggerDeadZone(Axis(s, PadAxis::kTriggerLeft), config_.trigger_dead_zone);
  return c;
}

BlimpCommand BlimpManualInterface::Step(double t_s, const InputState& s) {
  BlimpCommand c = config_.input() == BlimpManualInput::kKeys ? Keys(t_s, s) : Pad(s);
  last_t_s_ = t_s;
  started_ = true;
  c.camera_pan = s.head_pan;
  c.camera_tilt = s.head_tilt;
  return Clamped(c);
}

BlimpCommand BlimpManualInterface::Update(double t_s, const InputState& input, haptics::Hal& hal) {
  hal.SetField(haptics::Side::kLeft, haptics::ForceField{});
  hal.SetField(haptics::Side::kRight, haptics::ForceField{});
  return Step(t_s, input);
}

const char* BlimpManualInterface::Notice() const {
  const bool waiting = config_.input() == BlimpManualInput::kGamepad && !pad_connected_;
  return waiting && !lost_ ? kNoControllerNotice : nullptr;
}

const char* BlimpManualInterface::Help(bool /*switchable*/) const {
  if (config_.input() == BlimpManualInput::kGamepad) {
    return "left stick power (sideways: tail rotor), right stick elevator/rudder, triggers climb";
  }
  return "W/S power, up/down climb, A/D turn, PgUp/PgDn elevator, space neutral, drag to look";
}

namespace {

// The blimp by keys or a game controller in the catalogue (catalog.hpp): which
// of the two is the file's name (BlimpManualConfig::input).
const RegisterInterface<BlimpFamily, BlimpManualConfig> kBlimpManualInterfaces{
    {{.name = "blimp-keys",
      .family = VehicleFamily::kBlimp,
      .hands = {false, false},
      .input = InterfaceInput::kKeys,
      .physics = false,
      .summary = "the blimp by a person's keys"},
     {.name = "blimp-gamepad",
      .family = VehicleFamily::kBlimp,
      .hands = {false, false},
      .input = InterfaceInput::kGamepad,
      .physics = false,
      .summary = "the blimp by a person's game controller"}},
    LoadBlimpManual,
    [](const BlimpManualConfig& config, const InterfaceParts& parts) {
      return std::make_unique<BlimpManualInterface>(config,
                                                    PersonsInput(config.name, parts).Load());
    }};

}  // namespace

}  // namespace haptel::interfaces
