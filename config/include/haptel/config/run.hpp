#pragma once
/// @file The operator side's run configuration (config/haptel.yaml).
#include <filesystem>
#include <string>
#include <vector>

#include "haptel/config/archive.hpp"
#include "haptel/config/link.hpp"
#include "haptel/config/scene.hpp"

namespace haptel {

/// Where the pilot's camera head looks from (view/head_source.hpp): the
/// mouse dragged in the window, a game controller's right stick, or an
/// OpenXR head-mounted display's pose.
enum class HeadSourceKind { kMouse, kGamepad, kOpenXr };
const char* ToString(HeadSourceKind kind);

/// The head that turns a pan/tilt camera (`head:` in the run file;
/// `haptel run --head` overrides the source).
struct HeadConfig {
  HeadSourceKind source = HeadSourceKind::kMouse;
  /// The stick turns the head at this rate at full deflection (rate control:
  /// a released stick leaves the head where it looks), rad/s.
  double stick_rate_rad_s = 1.5;
  /// Deflection below this (radially, of 1) is no turn: a stick rests off centre.
  double stick_dead_zone = 0.15;

  template <typename Archive>
  void Serialize(Archive* a) {
    using K = HeadSourceKind;
    a->Visit(HAPTEL_NVP(source),
             config::Choice<K>{
                 {{K::kMouse, "mouse"}, {K::kGamepad, "gamepad"}, {K::kOpenXr, "openxr"}}});
    a->Visit(HAPTEL_NVP(stick_rate_rad_s), config::Range{0.1, 10.0});
    a->Visit(HAPTEL_NVP(stick_dead_zone), config::Range{0.0, 0.9});
  }
  void ValidateOrThrow() const;
};

/// The operator's view (`view:` in the run file; `haptel run --stereo`,
/// `--ipd-mm` override).
struct ViewConfig {
  /// Side by side for a head-mounted display: the left eye's picture in the
  /// window's left half, the right's in the right half.
  bool stereo = false;
  /// The eyes' distance apart, m (an adult's is 54-74 mm; 64 mm the mean).
  double ipd_m = 0.064;

  template <typename Archive>
  void Serialize(Archive* a) {
    a->Visit(HAPTEL_NVP(stereo));
    a->Visit(HAPTEL_NVP(ipd_m), config::Range{0.04, 0.09});
  }
  void ValidateOrThrow() const;
};

/// The automatic operator: a simulated person driving through the interface.
struct OperatorConfig {
  double reaction_delay_s = 0.15;
  double arm_time_constant_s = 0.1;     ///< lag of the hand target behind intent
  double lookahead = 0.35;              ///< pure-pursuit look-ahead, m
  double cruise = 0.9;                  ///< forward command on straights (0..1)
  double min_forward = 0.35;            ///< forward command in the tightest turn
  double slow_radius = 0.15;            ///< turn radius at which it slows to min_forward, m
  double muscle_stiffness = 250.0;      ///< N/m
  double muscle_damping = 12.0;         ///< N·s/m
  double muscle_max_force = 8.0;        ///< N
  double muscle_integral_gain = 400.0;  ///< N/(m·s): pushing harder against a pull
  double backoff_s = 0.8;               ///< reverse this long after a bumper contact
  /// After backing off, steer this long with full attention: a person who
  /// has just hit something aims the next attempt (half the look-ahead, no
  /// steering wander, and a control that stays put is brought exactly where
  /// it is wanted); hitting again meanwhile backs off longer each time.
  double careful_s = 4.0;
  /// Grasping a control (cockpit interfaces): come down onto it with an open
  /// hand for this long, then close the fingers over grasp_close_s.
  double grasp_reach_s = 0.8;
  double grasp_close_s = 0.6;
  /// The physiological tremor of a hand that holds an arm: every person's
  /// hand shakes at 8-12 Hz by about 0.1-0.5 mm even when held still
  /// (Elble & Koller, "Tremor", 1990), and the session knows a held arm by
  /// it (mediator/engagement.hpp; docs/haptics.md). The held hand's
  /// displacement amplitude along each axis, m (0: a hand that never shakes),
  /// and its frequency, each axis a few percent apart (the device's seed).
  double tremor_amplitude = 0.2e-3;
  double tremor_frequency_hz = 10.0;

  template <typename Archive>
  void Serialize(Archive* a) {
    using config::Range;
    a->Visit(HAPTEL_NVP(reaction_delay_s), Range{0.0, 2.0});
    a->Visit(HAPTEL_NVP(arm_time_constant_s), Range{0.0, 2.0});
    a->Visit(HAPTEL_NVP(lookahead), Range{0.05, 10.0});
    a->Visit(HAPTEL_NVP(cruise), Range{0.05, 1.0});
    a->Visit(HAPTEL_NVP(min_forward), Range{0.0, 1.0});
    a->Visit(HAPTEL_NVP(slow_radius), Range{0.0, 100.0});
    a->Visit(HAPTEL_NVP(muscle_stiffness), Range{1.0, 1e4});
    a->Visit(HAPTEL_NVP(muscle_damping), Range{0.0, 1e3});
    a->Visit(HAPTEL_NVP(muscle_max_force), Range{0.1, 100.0});
    a->Visit(HAPTEL_NVP(muscle_integral_gain), Range{0.0, 1e5});
    a->Visit(HAPTEL_NVP(backoff_s), Range{0.0, 10.0});
    a->Visit(HAPTEL_NVP(careful_s), Range{0.0, 60.0});
    a->Visit(HAPTEL_NVP(grasp_reach_s), Range{0.0, 10.0});
    a->Visit(HAPTEL_NVP(grasp_close_s), Range{0.0, 10.0});
    a->Visit(HAPTEL_NVP(tremor_amplitude), Range{0.0, 5e-3});
    a->Visit(HAPTEL_NVP(tremor_frequency_hz), Range{1.0, 30.0});
  }

  /// Throws ConfigFieldError unless every value is in range and min_forward <= cruise.
  void ValidateOrThrow() const;
};

struct RunConfig {
  std::filesystem::path file;
  std::string name = "default";
  std::filesystem::path track;
  std::filesystem::path vehicle;
  std::string interface = "gesture";
  /// The interfaces keys F1-F6 switch between during a run, in key order.
  std::vector<std::string> interfaces{"gesture",          "cockpit",  "cockpit-hud",
                                      "cockpit-assisted", "keyboard", "gamepad"};
  /// A person's run ends here unless --time-limit says otherwise (the thesis's 10-minute cap).
  double person_time_limit_s = 600.0;
  /// Forces ramp down and up over this when the interface changes.
  double switch_ramp_s = 0.3;
  std::filesystem::path interfaces_dir;  ///< where <interface>.yaml files live
  std::filesystem::path database = "runs/haptel.db";
  double vehicle_timeout_s = 0.5;  ///< no state for this long: vehicle lost
  double session_rate_hz = 100.0;
  bool video_decode = true;
  std::filesystem::path device;   ///< haptic device file (config/devices/*.yaml)
  std::filesystem::path physics;  ///< physics world file, for interfaces with bodies
  std::filesystem::path scene;    ///< haptic scene (YAML or MHaptic XML); empty: none
  /// Where the scene goes in the device frame (PlaceScene), from
  /// `scene_placement: {position: [x, y, z] (m), rpy_deg: [roll, pitch, yaw]}`
  /// (RotationFromRpyDeg); identity by default.
  ScenePlacement scene_placement;
  OperatorConfig op;
  LinkConfig link;
  HeadConfig head;
  ViewConfig view;

  template <typename Archive>
  void Serialize(Archive* a) {
    // Every field but `file` and `scene_placement` (read as a position and
    // roll, pitch, yaw: LoadRun). Paths are relative to the file's folder but
    // the database's, which is relative to the working directory.
    using config::MakeNameValue, config::Range, config::RelativeToFile, config::Required;
    a->Visit(HAPTEL_NVP(name), config::NonEmpty{});
    a->Visit(HAPTEL_NVP(track), Required{}, RelativeToFile{});
    a->Visit(HAPTEL_NVP(vehicle), Required{}, RelativeToFile{});
    a->Visit(HAPTEL_NVP(device), RelativeToFile{});
    a->Visit(HAPTEL_NVP(physics), RelativeToFile{});
    a->Visit(HAPTEL_NVP(scene), RelativeToFile{});
    a->Visit(HAPTEL_NVP(interface), config::NonEmpty{});
    a->Visit(MakeNameValue("switchable_interfaces", &interfaces));
    a->Visit(HAPTEL_NVP(interfaces_dir), RelativeToFile{});
    a->Visit(HAPTEL_NVP(database));
    a->Visit(HAPTEL_NVP(vehicle_timeout_s), Range{0.05, 60.0});
    a->Visit(HAPTEL_NVP(session_rate_hz), Range{10.0, 1000.0});
    a->Visit(HAPTEL_NVP(video_decode));
    a->Visit(HAPTEL_NVP(person_time_limit_s), Range{1.0, 86400.0});
    a->Visit(HAPTEL_NVP(switch_ramp_s), Range{0.01, 5.0});
    a->Visit(MakeNameValue("operator", &op));
    a->Visit(HAPTEL_NVP(link));
    a->Visit(HAPTEL_NVP(head));
    a->Visit(HAPTEL_NVP(view));
  }

  /// Throws ConfigFieldError (keys as in the file: "operator.cruise") unless
  /// the names and timing values are valid and every part is ("operator.*",
  /// "scene_placement.*", "link.*").
  void ValidateOrThrow() const;
};

/// Loads and validates (RunConfig::ValidateOrThrow) a run file (strict:
/// unknown keys are errors naming file, key and line).
RunConfig LoadRun(const std::filesystem::path& file);

/// The interface file for a name: `<interfaces_dir>/<name>.yaml`. Throws
/// ConfigError listing the available names when there is none.
std::filesystem::path InterfaceFile(const RunConfig& run, const std::string& name);

/// The `name` an interface file declares, which says which loader reads the
/// rest (`gesture`, or `cockpit*`). Throws ConfigError naming the file.
std::string InterfaceName(const std::filesystem::path& file);

}  // namespace haptel
