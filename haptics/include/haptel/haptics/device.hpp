#pragma once
/// @file The haptic device interface the servo loop drives.
///
/// A device has up to two arms (sides). Each arm has fast channels (wrist
/// tracker in, wrist force out, finger forces out), read and written every
/// servo cycle, and slow channels (glove sensors and grasp strings in), read
/// every N-th cycle. Values cross this interface in device units; the servo
/// loop applies the calibration.
#include <array>
#include <cstdint>
#include <limits>
#include <string>

#include "haptel/haptics/types.hpp"

namespace haptel::haptics {

enum class DeviceStatus {
  kOk,      ///< fresh reading / command accepted
  kNoData,  ///< no new reading this tick (keep the last one); not an error
  kLost,    ///< the device stopped answering: forces must be zero
};

/// Whether a person holds an arm, as the device itself can tell.
enum class HandPresence : uint8_t {
  kUnknown,   ///< it cannot tell (an exoskeleton, a replayed trace): the session infers it
  kHeld,      ///< a person holds it (a mouse button held in the window, a deadman pressed)
  kReleased,  ///< nobody holds it now
};

/// What a device measured of the person's use of it, for the run's record.
struct DeviceUseReport {
  /// How much the hand's motion was bent from the input's (a mouse's
  /// pseudo-haptics): the hand's displacement over the pointer's, mean over
  /// the ticks the pointer moved; NaN for a device that does not bend it.
  double pseudo_haptic_gain_mean = std::numeric_limits<double>::quiet_NaN();
  uint64_t ff_effects_played = 0;  ///< force-feedback effects started (SDL's haptic API)
  uint64_t shakes = 0;             ///< contact shakes shown or played
};

/// What a device that bends its hand's motion away from the person's input
/// (the mouse's pseudo-haptics, docs/haptics.md) shows of one side: where
/// the input alone would put the hand, where the hand is, what pushes it and
/// how it shakes. Device units as ReadWrist's and WriteWristForce's (the
/// servo loop publishes it into the HAL in metres and newtons).
struct PseudoHapticReport {
  Vec3d target{};  ///< where the input alone puts the hand
  Vec3d hand{};    ///< where the hand is (what ReadWrist reports)
  Vec3d force{};   ///< the wrist force last written
  Vec3d shake{};   ///< the shown hand's offset from `hand` now (a contact's shake; zero when none)
  bool held = false;           ///< the input moves the hand now (else it is free)
  uint64_t shakes = 0;         ///< shakes started on this side so far
  int64_t shake_start_ns = 0;  ///< servo time (CLOCK_MONOTONIC) the newest one started; 0: none
};

/// What a device is and may be asked: from its driver or its YAML file.
struct DeviceDescription {
  std::string name = "device";
  std::array<bool, kSides> has_side{true, true};
  double wrist_force_limit = 7.0;    ///< N at the wrist
  double finger_force_limit = 10.0;  ///< N per finger
  bool has_glove = true;
  bool has_grasp = true;
};

/// One end's two-port passivity report across a device's link (twoport.hpp),
/// SI: what crossed the channel at that end and what its controller did.
/// Every field is a monotone counter (max_alpha a running maximum) until the
/// link's observers restart.
struct LinkEnergy {
  Vec3d energy_in{};          ///< J per axis: what entered the channel at that end
  Vec3d charged{};            ///< J per axis: deficit that end could not dissipate itself
  double dissipated_j = 0.0;  ///< J, that end's controller, all axes
  uint64_t acted_ticks = 0;   ///< ticks that end's controller acted
  double max_alpha = 0.0;     ///< the largest damping that end's controller added, N·s/m
};

/// Every call except description() comes from the servo thread that owns
/// `side`; in two-sided mode the two sides run on two threads at once, so an
/// implementation must keep per-side state apart. Calls must not allocate and
/// must not block beyond the device's own I/O (bounded by its timeouts).
class Device {
 public:
  virtual ~Device() = default;
  virtual const DeviceDescription& description() const = 0;
  bool HasSide(Side side) const { return description().has_side[Index(side)]; }

  /// Fast channel: the wrist tracker at servo time `now_ns`.
  virtual DeviceStatus ReadWrist(Side side, int64_t now_ns, WristRaw& out) = 0;
  /// Slow channels: glove sensors and grasp strings.
  virtual DeviceStatus ReadGlove(Side side, int64_t now_ns, GloveRaw& out) = 0;
  /// Wrist force command, device units (newtons / calibrated slope).
  virtual DeviceStatus WriteWristForce(Side side, const Vec3d& command) = 0;
  /// Finger force commands, device units, each ≥ 0.
  virtual DeviceStatus WriteFingerForces(Side side,
                                         const std::array<double, kFingers>& command) = 0;

  /// Whether a person holds `side` now, when the device can tell. Servo
  /// thread, every tick after ReadWrist; must not block.
  virtual HandPresence Presence(Side side) {
    (void)side;
    return HandPresence::kUnknown;
  }
  /// The tick's set-point, which the force written next is computed from:
  /// for a device that renders part of it itself (the sdl-ff device plays
  /// the field's centring as its own spring, its wall as a shake). Servo
  /// thread, every tick the arm answers, before WriteWristForce; must not
  /// block or allocate. Forces come from WriteWristForce alone otherwise.
  virtual void SetpointHint(Side side, const ForceSetpoint& setpoint) {
    (void)side;
    (void)setpoint;
  }
  /// Why the device answers kLost when the person took it away (a joystick
  /// unplugged): a line saying so, and the run ends aborted, as when a game
  /// controller is disconnected. "" (the default): lost is the device's
  /// fault (the run ends "device lost"). Any thread.
  virtual std::string UnpluggedLine() const { return {}; }
  /// Its use so far. Any thread (an implementation keeps it in atomics).
  virtual DeviceUseReport UseReport() const { return {}; }
  /// A device that bends its hand's motion (pseudo-haptics) fills `out` and
  /// returns true; others false. Servo thread, every tick after ReadWrist.
  virtual bool PseudoHaptics(Side side, PseudoHapticReport& out) {
    (void)side;
    (void)out;
    return false;
  }

  // Two-port passivity across the device's link (a device whose arms sit
  // behind a network: the udp driver's protocol version 2). A local device
  // keeps the defaults: no link, nothing to exchange.

  /// Whether the arms sit behind a link that can carry passivity reports.
  /// Constant for a device's life: the servo loop observes the link's port
  /// only when it is true (a local device pays nothing for it).
  virtual bool HasLink() const { return false; }
  /// True when the far end of `side`'s link observes its port and runs its
  /// controller (and reports it); `remote` is then its newest report.
  virtual bool LinkPassivity(Side side, LinkEnergy& remote) {
    (void)side;
    (void)remote;
    return false;
  }
  /// The loop's end's report, sent with the next commands (and every later
  /// one until replaced); tells the far end the loop observes its port.
  virtual void SetLinkEnergy(Side side, const LinkEnergy& local) {
    (void)side;
    (void)local;
  }
  /// Both ends start counting from zero again (the loop's end was reset:
  /// the arm was lost, or the observers start afresh).
  virtual void RestartLinkEnergy(Side side) { (void)side; }
};

}  // namespace haptel::haptics
