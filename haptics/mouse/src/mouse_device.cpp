#include "haptel/mouse/mouse_device.hpp"

#include <algorithm>
#include <cmath>

namespace haptel::haptics {

namespace {

double Norm(const Vec3d& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

/// The wrist turned `deg` about z, as a quaternion (w, x, y, z).
std::array<double, 4> Yaw(double deg) {
  const double half = 0.5 * deg * M_PI / 180.0;
  return {std::cos(half), 0.0, 0.0, std::sin(half)};
}

/// Longer ticks than this (a stalled loop) are stepped as this long: the
/// free hand's explicit step stays stable under any field the shipped
/// interfaces set.
constexpr double kMaxStepS = 0.01;

}  // namespace

std::array<double, kGloveJoints> MouseDevice::ClosedGlove() {
  // Glove layout (types.hpp): four thumb joints, then MCP, PIP, DIP of the
  // index, middle, ring and pinky. GripGeometry::flexion's values.
  constexpr std::array<double, 3> kFlexion{0.2, 1.6, 1.4};
  std::array<double, kGloveJoints> closed{};
  for (int f = 0; f < 4; ++f) {
    for (int j = 0; j < 3; ++j) closed[static_cast<size_t>(4 + 3 * f + j)] = kFlexion[j];
  }
  return closed;
}

MouseDevice::MouseDevice(const DeviceConfig& config, const PointerBox& pointer)
    : config_(config.mouse), pointer_box_(pointer), closed_(ClosedGlove()) {
  config_.ValidateOrThrow();
  description_.name = config.name;
  description_.has_side = config.sides;
  // The forces are shown, not felt: what the device may be asked is what the
  // device file's safety allows.
  description_.wrist_force_limit = config.safety.wrist_force_limit;
  description_.finger_force_limit = 0.0;
  description_.has_glove = true;
  description_.has_grasp = false;
  for (int i = 0; i < kSides; ++i) {
    Hand& h = hands_[static_cast<size_t>(i)];
    h.pointer = (i == Index(Side::kLeft)) == config_.pointer_on_left;
    const Vec3d rest = h.pointer ? config_.centre : config_.key_hand_rest;
    h.target = h.hand = h.window_hand = h.window_target = rest;
    h.orientation = Yaw(h.pointer ? config_.pointer_hand_yaw_deg : config_.key_hand_yaw_deg);
  }
}

void MouseDevice::Step(Hand& h, const PointerState& pointer, double dt_s) {
  const MouseDeviceConfig& c = config_;
  if (h.pointer) {
    // No window (yet): the target stays where it was.
    if (pointer.window_open && pointer.width_px > 0) h.target = PointerTarget(pointer, c);
  } else {
    h.target = StepKeyHand(h.target, pointer, c, dt_s);
  }
  h.coupled = pointer.window_open && pointer.in_window;
  h.held = h.coupled && pointer.grasp_button;
  const double tau = c.coupling_time_constant_s;
  const double dt = std::min(dt_s, kMaxStepS);
  if (h.coupled) {
    // Exact for the tick with F held: H relaxes towards T + F/k_c.
    const double keep = std::exp(-dt / tau);
    for (int i = 0; i < 3; ++i) {
      const double rest = h.target[i] + h.force[i] / c.coupling_stiffness;
      h.hand[i] = rest + (h.hand[i] - rest) * keep;
    }
  } else {
    for (int i = 0; i < 3; ++i) h.hand[i] += dt * h.force[i] / (tau * c.coupling_stiffness);
  }
}

void MouseDevice::StartShake(Hand& h, const Vec3d& direction, double amplitude_m) {
  // A shake already running plays on: its own motion steps the force too.
  if (h.shaking) return;
  h.shaking = true;
  h.shake_start_ns = h.last_ns;
  h.shake_direction = direction;
  h.shake_amplitude = std::min(kMaxShakeM, amplitude_m);
  ++h.shakes;
  shakes_.fetch_add(1, std::memory_order_relaxed);
}

void MouseDevice::UpdateShake(Hand& h, int64_t now_ns) {
  h.shake = Vec3d{};
  if (!h.shaking) return;
  const double t = static_cast<double>(now_ns - h.shake_start_ns) * 1e-9;
  if (t >= config_.shake_s) {
    h.shaking = false;
    return;
  }
  // Decays to e⁻³ (5 %) by its end.
  const double envelope = std::exp(-3.0 * t / std::max(config_.shake_s, 1e-6));
  const double s = h.shake_amplitude * envelope * std::sin(2.0 * M_PI * config_.shake_hz * t);
  for (int i = 0; i < 3; ++i) h.shake[i] = s * h.shake_direction[i];
}

void MouseDevice::MeasureGain(Hand& h, int64_t now_ns) {
  if (h.window_start_ns == 0) h.window_start_ns = now_ns;
  if (static_cast<double>(now_ns - h.window_start_ns) * 1e-9 < kGainWindowS) return;
  Vec3d moved_target{}, moved_hand{};
  for (int i = 0; i < 3; ++i) {
    moved_target[i] = h.target[i] - h.window_target[i];
    moved_hand[i] = h.hand[i] - h.window_hand[i];
  }
  const double pointer_m = Norm(moved_target);
  // Only windows the person drove the hand through count: a free hand's
  // motion is the field's, not a bent pointer's.
  if (h.held && pointer_m >= kGainFloorM) {
    gain_sum_.fetch_add(Norm(moved_hand) / pointer_m, std::memory_order_relaxed);
    gain_windows_.fetch_add(1, std::memory_order_relaxed);
  }
  h.window_start_ns = now_ns;
  h.window_hand = h.hand;
  h.window_target = h.target;
}

DeviceStatus MouseDevice::ReadWrist(Side side, int64_t now_ns, WristRaw& out) {
  Hand& h = hands_[static_cast<size_t>(Index(side))];
  PointerState& pointer = pointer_[static_cast<size_t>(Index(side))];
  pointer_box_.TryLoad(pointer);  // a store in progress: last tick's pointer
  const double dt =
      h.last_ns != 0 && now_ns > h.last_ns ? static_cast<double>(now_ns - h.last_ns) * 1e-9 : 0.0;
  h.last_ns = now_ns;
  const bool was_held = h.held;
  Step(h, pointer, dt);
  if (h.held != was_held) {
    // Held or let go: the window starts afresh, so one is all held or all free.
    h.window_start_ns = now_ns;
    h.window_hand = h.hand;
    h.window_target = h.target;
  }
  UpdateShake(h, now_ns);
  MeasureGain(h, now_ns);
  out.t_ns = now_ns;
  out.position = h.hand;
  out.orientation = h.orientation;
  return DeviceStatus::kOk;
}

DeviceStatus MouseDevice::ReadGlove(Side side, int64_t now_ns, GloveRaw& out) {
  const Hand& h = hands_[static_cast<size_t>(Index(side))];
  out.t_ns = now_ns;
  if (h.held) {
    out.sensors = closed_;
  } else {
    out.sensors = {};
  }
  out.grasp = {};
  return DeviceStatus::kOk;
}

DeviceStatus MouseDevice::WriteWristForce(Side side, const Vec3d& command) {
  hands_[static_cast<size_t>(Index(side))].force = command;
  return DeviceStatus::kOk;
}

void MouseDevice::SetpointHint(Side side, const ForceSetpoint& setpoint) {
  Hand& h = hands_[static_cast<size_t>(Index(side))];
  const uint64_t seen = h.contacts_seen;
  h.contacts_seen = setpoint.contacts;
  // The pointer hand shows a contact of the vehicle, and only that: the
  // forces a driven control or a field bring step often (a cockpit's lever
  // in its hand), a contact seldom, and a shake must mean one.
  if (!h.pointer || setpoint.contacts <= seen) return;
  // Pushed back from the contact: against the gesture's wall where one is up
  // (it rises on the contact), else backwards (the vehicle's bumpers are in front).
  const ForceField& field = setpoint.field;
  const bool wall = field.enabled && field.wall_active;
  StartShake(h, wall ? field.wall_normal : Vec3d{-1.0, 0.0, 0.0}, config_.shake_amplitude);
}

DeviceStatus MouseDevice::WriteFingerForces(Side, const std::array<double, kFingers>&) {
  return DeviceStatus::kOk;  // no strings: finger forces have nowhere to go
}

HandPresence MouseDevice::Presence(Side side) {
  return hands_[static_cast<size_t>(Index(side))].held ? HandPresence::kHeld
                                                       : HandPresence::kReleased;
}

DeviceUseReport MouseDevice::UseReport() const {
  DeviceUseReport r;
  const uint64_t windows = gain_windows_.load(std::memory_order_relaxed);
  if (windows > 0)
    r.pseudo_haptic_gain_mean =
        gain_sum_.load(std::memory_order_relaxed) / static_cast<double>(windows);
  r.shakes = shakes_.load(std::memory_order_relaxed);
  return r;
}

bool MouseDevice::PseudoHaptics(Side side, PseudoHapticReport& out) {
  const Hand& h = hands_[static_cast<size_t>(Index(side))];
  out.target = h.target;
  out.hand = h.hand;
  out.force = h.force;
  out.shake = h.shake;
  out.held = h.held;
  out.shakes = h.shakes;
  out.shake_start_ns = h.shakes > 0 ? h.shake_start_ns : 0;
  return true;
}

}  // namespace haptel::haptics
