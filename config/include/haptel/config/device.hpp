#pragma once
/// @file A haptic device's configuration (config/devices/*.yaml): which
/// driver, what the device may be asked, how the servo loop runs it, its
/// safety limits, and the files that calibrate and gravity-compensate it.
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "haptel/config/archive.hpp"

namespace haptel {

/// How the servo loop runs.
struct ServoLoopConfig {
  double rate_hz = 1000.0;
  /// One sub-thread per arm meeting at a rendezvous every cycle (the original's
  /// scheme); false: both arms on one thread, one after the other.
  bool two_sided = true;
  /// Slow channels (glove, grasp strings) are read every N-th cycle.
  int slow_channel_divider = 6;
  int realtime_priority = 80;  ///< SCHED_FIFO priority when the process may (0: do not ask)
  bool lock_memory = true;     ///< mlockall when the process may
  /// The time-domain passivity observer and controller on the wrist ports
  /// (haptel/haptics/passivity.hpp); `passivity: on|off` in the file.
  bool passivity = false;
  /// N·s/m: the most damping the controller may add, the device's largest
  /// stable damping (a figure of the device, like its force limit).
  double passivity_max_damping = 20.0;
  /// m/s: the controller's floor on |v|, so α = −E/(T·v²) stays finite near rest.
  double passivity_min_speed = 0.002;
  /// Across a device's link (the udp driver, protocol v2), what the servo
  /// loop's end of the two-port does with a deficit (haptel/haptics/twoport.hpp):
  /// false, `passivity_link: charge` (the default), it charges it to the
  /// arm's end, whose damping covers it; true, `passivity_link: admittance`,
  /// it dissipates it itself on the virtual environment's port (an offset on
  /// the position the environment reads). The arm's end damps the arm in
  /// both. Charge is the default because `haptel bench passivity` finds the
  /// admittance's stability bought by a wall that yields (its offset drifts
  /// to the cap under a sustained press): 8× the stiffness at 3 ms, but 3.3 N
  /// of force error where charge keeps 0.37 N (docs/benchmarks.md).
  bool passivity_link_admittance = false;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(rate_hz), config::Range{100.0, 10000.0});
    a->Visit(HAPTEL_NVP(two_sided));
    a->Visit(HAPTEL_NVP(slow_channel_divider), config::Range{1, 1000});
    a->Visit(HAPTEL_NVP(realtime_priority), config::Range{0, 99});
    a->Visit(HAPTEL_NVP(lock_memory));
    a->Visit(HAPTEL_NVP(passivity),
             config::Choice<bool>{{{true, "on"}, {false, "off"}}, "on or off"});
    a->Visit(
        config::MakeNameValue("passivity_link", &passivity_link_admittance),
        config::Choice<bool>{{{true, "admittance"}, {false, "charge"}}, "admittance or charge"});
    a->Visit(HAPTEL_NVP(passivity_max_damping), config::Range{0.0, 1e4});
    a->Visit(HAPTEL_NVP(passivity_min_speed), config::Range{1e-6, 1.0});
  }

  /// Throws ConfigFieldError unless the rate, divider, priority and the
  /// passivity limits are in range.
  void ValidateOrThrow() const;
};

/// Force safety, applied in the servo loop to every force before the device.
struct SafetyConfig {
  double wrist_force_limit = 7.0;    ///< N (also capped by the device description)
  double finger_force_limit = 10.0;  ///< N
  double max_force_rate = 2000.0;    ///< N/s, per axis / finger
  double soft_start_s = 0.5;         ///< forces ramp in after connect or reconnect
  double setpoint_timeout_s = 0.02;  ///< set-points older than this are stale
  double fade_s = 0.03;              ///< stale set-points fade to zero over this

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(wrist_force_limit), config::Range{0.0, 200.0});
    a->Visit(HAPTEL_NVP(finger_force_limit), config::Range{0.0, 100.0});
    a->Visit(HAPTEL_NVP(max_force_rate), config::Range{1.0, 1e6});
    a->Visit(HAPTEL_NVP(soft_start_s), config::Range{0.0, 60.0});
    a->Visit(HAPTEL_NVP(setpoint_timeout_s), config::Range{0.001, 10.0});
    a->Visit(HAPTEL_NVP(fade_s), config::Range{0.0, 10.0});
  }

  /// Throws ConfigFieldError unless every value is in range and
  /// setpoint_timeout_s + fade_s <= 0.05 (forces gone 50 ms after a stall).
  void ValidateOrThrow() const;
};

/// The simulated device: point-mass arms moved by a simulated operator, with
/// the imperfections calibration and gravity compensation must fix.
struct SimArmConfig {
  double arm_mass = 0.8;              ///< kg
  double damping = 1.0;               ///< N·s/m viscous
  double coulomb_friction = 0.3;      ///< N
  double exo_unbalanced_mass = 0.6;   ///< kg at the worst place in the workspace
  double encoder_resolution = 60e-6;  ///< m
  double force_limit = 7.0;           ///< N the hardware saturates at
  double glove_noise = 0.0;           ///< raw units, standard deviation
  /// Workspace box (hard stops), m, device frame.
  std::array<double, 3> workspace_min{-0.20, -0.30, -0.20};
  std::array<double, 3> workspace_max{0.30, 0.30, 0.25};
  /// Seed of the hidden "true" calibration parameters (scale, offsets, gains).
  int seed = 1;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(arm_mass), config::Range{0.01, 100.0});
    a->Visit(HAPTEL_NVP(damping), config::Range{0.0, 1e3});
    a->Visit(HAPTEL_NVP(coulomb_friction), config::Range{0.0, 100.0});
    a->Visit(HAPTEL_NVP(exo_unbalanced_mass), config::Range{0.0, 20.0});
    a->Visit(HAPTEL_NVP(encoder_resolution), config::Range{0.0, 0.01});
    a->Visit(HAPTEL_NVP(force_limit), config::Range{0.0, 200.0});
    a->Visit(HAPTEL_NVP(glove_noise), config::Range{0.0, 100.0});
    a->Visit(HAPTEL_NVP(workspace_min), config::Range{-5.0, 5.0});
    a->Visit(HAPTEL_NVP(workspace_max), config::Range{-5.0, 5.0});
    a->Visit(HAPTEL_NVP(seed), config::Range{0, 1 << 30});
  }

  /// Throws ConfigFieldError unless every value is in range and
  /// workspace_min < workspace_max on every axis.
  void ValidateOrThrow() const;
};

struct UdpArmEndpoint {
  std::string host = "127.0.0.1";
  int port = 0;  ///< 0: no arm on this side

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(host), config::NonEmpty{});
    a->Visit(HAPTEL_NVP(port), config::Range{0, 65535});
  }

  /// Throws ConfigFieldError unless the host is set and the port in [0, 65535].
  void ValidateOrThrow() const;
};

struct UdpDeviceConfig {
  std::array<UdpArmEndpoint, 2> arms;  ///< [left, right]
  double timeout_s = 0.002;            ///< per request
  int retries = 1;                     ///< extra attempts after a timeout
  double lost_after_s = 0.1;           ///< no valid answer for this long: device lost

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(config::MakeNameValue("left", &arms[0]));
    a->Visit(config::MakeNameValue("right", &arms[1]));
    a->Visit(HAPTEL_NVP(timeout_s), config::Range{1e-5, 5.0});
    a->Visit(HAPTEL_NVP(retries), config::Range{0, 100});
    a->Visit(HAPTEL_NVP(lost_after_s), config::Range{1e-3, 60.0});
  }

  /// Throws ConfigFieldError unless the endpoints ("left.*", "right.*") and
  /// the timing values are valid.
  void ValidateOrThrow() const;
};

/// The `mouse` device (haptics/mouse): a person's mouse and keys as the
/// device's two hands, forces shown by pseudo-haptics (docs/haptics.md).
///
/// The pointer moves `pointer_hand` absolutely: the window's centre is
/// `centre`, pointer up is +x (forward), pointer right is −y (the device's y
/// is to the left), `metres_per_pixel` apart; the scroll wheel moves it in z
/// by `wheel_step` a notch. The other hand is the key hand: W/S, A/D and Q/E
/// (and the arrows) move it in ±x, ±y and ±z at `key_hand_speed`; released,
/// it goes back to `key_hand_rest` at that speed. The grasp button (the left
/// one) closes both hands; the device counts the pointer hand held while the
/// pointer is in the window and that button is down.
///
/// Forces bend the hand away from the pointer's place: the hand follows its
/// target through a virtual coupling of `coupling_stiffness` whose time
/// constant is `coupling_time_constant_s`, so a field of stiffness k lets the
/// hand move k_c / (k_c + k) of the pointer's motion (Lécuyer's
/// control/display ratio), and a contact of the vehicle shakes it.
/// The coupling's damping, τ·k_c, must stay well above the damping of what
/// pushes the hand (the servo loop's force lags a tick and its velocity is
/// filtered): 0.06 s × 100 N/m holds the gesture's wall (1500 N/m, 77 N·s/m)
/// without chatter (tests/haptics/mouse/test_mouse_device.cpp); 0.02 s
/// chatters by millimetres there.
/// The forces are not felt, so the device file's safety limits may be far
/// above an arm's: a wall holds the hand only up to the force limit.
struct MouseDeviceConfig {
  std::array<double, 3> centre{0.0, 0.0, 0.0};  ///< m, device frame: the window's centre
  double metres_per_pixel = 0.0005;
  double wheel_step = 0.005;  ///< m per wheel notch
  /// `pointer_hand: left|right` in the file; the other hand is the key hand.
  bool pointer_on_left = false;
  double key_hand_speed = 0.15;                        ///< m/s
  std::array<double, 3> key_hand_rest{0.0, 0.0, 0.0};  ///< m, device frame
  double coupling_stiffness = 100.0;                   ///< N/m
  double coupling_time_constant_s = 0.06;
  double shake_amplitude = 0.008;  ///< m, a contact's shake (at most 0.01 m)
  double shake_hz = 12.0;
  double shake_s = 0.3;
  /// Each hand's wrist turned about z (up), degrees, positive to the left:
  /// the grip the interface's controls want (the cockpit holds its lever
  /// turned −90°, the fingers across the bar; its wheel at 0).
  double pointer_hand_yaw_deg = 0.0;
  double key_hand_yaw_deg = 0.0;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(centre), config::Range{-5.0, 5.0});
    a->Visit(HAPTEL_NVP(metres_per_pixel), config::Range{1e-6, 0.1});
    a->Visit(HAPTEL_NVP(wheel_step), config::Range{0.0, 0.1});
    a->Visit(config::MakeNameValue("pointer_hand", &pointer_on_left),
             config::Choice<bool>{{{true, "left"}, {false, "right"}}, "left or right"});
    a->Visit(HAPTEL_NVP(key_hand_speed), config::Range{0.0, 10.0});
    a->Visit(HAPTEL_NVP(key_hand_rest), config::Range{-5.0, 5.0});
    a->Visit(HAPTEL_NVP(coupling_stiffness), config::Range{1.0, 1e5});
    a->Visit(HAPTEL_NVP(coupling_time_constant_s), config::Range{1e-4, 10.0});
    a->Visit(HAPTEL_NVP(shake_amplitude), config::Range{0.0, 0.01});
    a->Visit(HAPTEL_NVP(shake_hz), config::Range{0.1, 200.0});
    a->Visit(HAPTEL_NVP(shake_s), config::Range{0.0, 10.0});
    a->Visit(HAPTEL_NVP(pointer_hand_yaw_deg), config::Range{-180.0, 180.0});
    a->Visit(HAPTEL_NVP(key_hand_yaw_deg), config::Range{-180.0, 180.0});
  }
  /// Throws ConfigFieldError unless every value is in range.
  void ValidateOrThrow() const;
};

/// Where an `sdl-ff` axis rests: a stick at its centre (deflection in
/// [−1, 1]); a pedal or trigger at one end of SDL's range, low (−32768) or
/// high (32767: many wheels' pedals), its deflection in [0, 1] from there.
enum class SdlFfAxisRest : uint8_t { kCentre, kLow, kHigh };

/// One coordinate of an `sdl-ff` hand that an axis moves: the hand's centre
/// plus `span` times the axis' deflection. A second axis (a brake pedal,
/// resting where `rest` says, or low for a stick) may move it the other way.
struct SdlFfAxisMap {
  int axis = -1;      ///< SDL's axis index; −1: the coordinate stays at the centre
  double span = 0.0;  ///< m at full deflection; its sign says which way
  SdlFfAxisRest rest = SdlFfAxisRest::kCentre;
  int reverse_axis = -1;  ///< −1: none
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(axis), config::Range{-1, 63});
    a->Visit(HAPTEL_NVP(span), config::Range{-1.0, 1.0});
    a->Visit(HAPTEL_NVP(rest), config::Choice<SdlFfAxisRest>{{{SdlFfAxisRest::kCentre, "centre"},
                                                              {SdlFfAxisRest::kLow, "low"},
                                                              {SdlFfAxisRest::kHigh, "high"}}});
    a->Visit(HAPTEL_NVP(reverse_axis), config::Range{-1, 63});
  }
  void ValidateOrThrow() const;
};

/// A wheel's axis moving a hand around the rim: the hand on the circle of
/// `radius` about the hand's centre in the y–z plane, at angle θ =
/// `angle_deg` × deflection from the top (+θ: to the left, turned about
/// −x as the cockpit's wheel turns), its orientation turned with it.
struct SdlFfRimMap {
  int axis = -1;            ///< −1: no rim
  double radius = 0.143;    ///< m, hub to wrist (the cockpit: rim 0.12 + grip height 0.023)
  double angle_deg = -135;  ///< at full deflection (a wheel turned right turns the rim right: −)
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(axis), config::Range{-1, 63});
    a->Visit(HAPTEL_NVP(radius), config::Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(angle_deg), config::Range{-720.0, 720.0});
  }
  void ValidateOrThrow() const;
};

/// One hand of an `sdl-ff` device: where it is with every axis at rest, how
/// it is turned, and which axes move it (per coordinate, or around a rim).
struct SdlFfHandMap {
  std::array<double, 3> centre{0.0, 0.0, 0.0};  ///< m, device frame (a rim's hub)
  /// deg: roll, pitch, yaw (about x, y, z, applied z then y then x)
  std::array<double, 3> orientation_deg{0.0, 0.0, 0.0};
  SdlFfAxisMap x, y, z;
  SdlFfRimMap rim;  ///< moves y and z: leave their axes at −1
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(centre), config::Range{-5.0, 5.0});
    a->Visit(HAPTEL_NVP(orientation_deg), config::Range{-360.0, 360.0});
    a->Visit(HAPTEL_NVP(x));
    a->Visit(HAPTEL_NVP(y));
    a->Visit(HAPTEL_NVP(z));
    a->Visit(HAPTEL_NVP(rim));
  }
  /// Throws ConfigFieldError unless the fields are in range and a rim
  /// leaves y and z alone.
  void ValidateOrThrow() const;
};

/// The deadman (ROS teleop_twist_joy's enable_button): a button, or an axis
/// (a trigger or pedal resting low or high) pressed past `threshold` of its travel.
struct SdlFfDeadman {
  int button = 0;          ///< −1: an axis instead
  int axis = -1;           ///< −1: a button instead
  bool rest_high = false;  ///< `rest: low|high`
  double threshold = 0.5;
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(button), config::Range{-1, 63});
    a->Visit(HAPTEL_NVP(axis), config::Range{-1, 63});
    a->Visit(config::MakeNameValue("rest", &rest_high),
             config::Choice<bool>{{{true, "high"}, {false, "low"}}, "low or high"});
    a->Visit(HAPTEL_NVP(threshold), config::Range{0.0, 1.0});
  }
  /// Throws ConfigFieldError unless exactly one of button and axis is set.
  void ValidateOrThrow() const;
};

/// The `sdl-ff` device (haptics/sdl_ff, docs/haptics.md): a joystick or
/// wheel SDL opens, its axes as the hands' positions (metres, so the device
/// calibrates itself) and its force feedback as their forces: the
/// interface's centring field as the device's spring, the rest of the wrist
/// force as a constant force, a contact as a sine shake (or rumble on a
/// device with rumble only), all at `effect_hz`. The device's full effect
/// level is `safety.wrist_force_limit` newtons at the hand.
struct SdlFfDeviceConfig {
  /// Which joystick: its index in SDL's list, or −1 for the first that has
  /// force feedback (else the first with rumble).
  int joystick = -1;
  SdlFfDeadman deadman;
  SdlFfHandMap left, right;
  double poll_hz = 250.0;    ///< the I/O thread reads the axes this often
  double effect_hz = 100.0;  ///< and updates the effects this often
  /// A contact of the vehicle (ForceSetpoint::contacts) plays a shake.
  double shake_level = 0.6;  ///< of the device's full effect level
  double shake_hz = 12.0;
  double shake_s = 0.3;
  /// The hands close (four fingers' MCP, PIP, DIP, rad) while the deadman is
  /// held: the cockpit's grip.
  std::array<double, 3> grasp_flexion{0.2, 1.6, 1.4};
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(joystick), config::Range{-1, 63});
    a->Visit(HAPTEL_NVP(deadman));
    a->Visit(HAPTEL_NVP(left));
    a->Visit(HAPTEL_NVP(right));
    a->Visit(HAPTEL_NVP(poll_hz), config::Range{10.0, 2000.0});
    a->Visit(HAPTEL_NVP(effect_hz), config::Range{1.0, 1000.0});
    a->Visit(HAPTEL_NVP(shake_level), config::Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(shake_hz), config::Range{0.1, 200.0});
    a->Visit(HAPTEL_NVP(shake_s), config::Range{0.0, 10.0});
    a->Visit(HAPTEL_NVP(grasp_flexion), config::Range{-3.2, 3.2});
  }
  /// Throws ConfigFieldError unless every value is in range and the hands
  /// and the deadman are valid ("right.rim.axis", "deadman.button").
  void ValidateOrThrow() const;
};

struct ReplayDeviceConfig {
  std::filesystem::path trace;  ///< a trace file written by the session recorder
  bool loop = false;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(trace), config::RelativeToFile{});
    a->Visit(HAPTEL_NVP(loop));
  }

  /// Nothing to check on its own (DeviceConfig requires a trace for the
  /// replay driver); there for uniformity: never throws.
  void ValidateOrThrow() const;
};

struct DeviceConfig {
  std::filesystem::path file;
  std::string name = "sim";
  std::string driver = "sim";             ///< a registered driver's name (sim, udp, replay)
  std::array<bool, 2> sides{true, true};  ///< [left, right]
  bool has_glove = true;
  bool has_grasp = true;
  ServoLoopConfig servo;
  SafetyConfig safety;
  SimArmConfig sim;
  UdpDeviceConfig udp;
  ReplayDeviceConfig replay;
  MouseDeviceConfig mouse;
  SdlFfDeviceConfig sdl_ff;
  /// Optional files (empty: none). Relative paths resolve against the working directory.
  std::filesystem::path calibration;
  std::filesystem::path gravity;

  /// Every field but `file` and `sides` (a list of side names, read by LoadDevice).
  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(name), config::Required{}, config::NonEmpty{});
    a->Visit(HAPTEL_NVP(driver));
    a->Visit(HAPTEL_NVP(has_glove));
    a->Visit(HAPTEL_NVP(has_grasp));
    a->Visit(HAPTEL_NVP(calibration));
    a->Visit(HAPTEL_NVP(gravity));
    a->Visit(HAPTEL_NVP(servo));
    a->Visit(HAPTEL_NVP(safety));
    a->Visit(HAPTEL_NVP(sim));
    a->Visit(HAPTEL_NVP(udp));
    a->Visit(HAPTEL_NVP(replay));
    a->Visit(HAPTEL_NVP(mouse));
    a->Visit(HAPTEL_NVP(sdl_ff));
  }

  /// Throws ConfigFieldError unless the driver is registered, a side is used,
  /// the parts are valid ("servo.*", "safety.*", ...) and the driver's own
  /// checks pass (the udp driver's port for every side used, the replay
  /// driver's trace).
  void ValidateOrThrow() const;
};

/// Makes `driver` a name a device file may give, with its own checks of the
/// file (ConfigFieldError; may be empty). config/ is below the drivers, so it
/// names none: each driver's descriptor adds itself as it registers
/// (haptics/device_drivers.hpp), and a program that loads device files links
/// the drivers. std::invalid_argument when the name is taken. Register before
/// any thread validates a device.
void AddDeviceDriverCheck(const std::string& driver,
                          std::function<void(const DeviceConfig&)> check);

/// Loads and validates (DeviceConfig::ValidateOrThrow) a device file (strict:
/// unknown keys are errors naming file, key and line).
DeviceConfig LoadDevice(const std::filesystem::path& file);

}  // namespace haptel
