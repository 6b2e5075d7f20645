#pragma once
/// @file Whether the operator engages the interface now: a hand that lets go
/// stops the vehicle (issue 36).
///
/// An interface driven by hands on the device drives only while every hand
/// it uses is held — the device's own word when it gives one (the mouse's
/// button in the window, a joystick's deadman: Device::Presence, published
/// into the HAL), else inferred from the hand's motion (MeasureHandMotion:
/// a held hand shakes with physiological tremor, an arm nobody holds
/// settles and stays still) — and within reach of the interface's neutral.
/// After being disengaged it engages again only once the interface's
/// command is back at rest, so that a hand grabbed away from neutral does
/// not lurch the vehicle. Keys and game controllers are engaged by holding
/// them already (hold-to-drive: released, their command is zero) and are
/// always engaged here. docs/haptics.md, "A hand that lets go", says how
/// and why.
#include <array>
#include <optional>
#include <span>
#include <vector>

#include "haptel/config/calibration.hpp"
#include "haptel/core/blimp_command.hpp"
#include "haptel/core/tread_command.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/interfaces/interface.hpp"

namespace haptel::mediator {

/// How a held hand's motion is told from an arm nobody holds.
struct HandMotionRule {
  /// The newest stretch of the tracker's history judged.
  static constexpr double kWindow_s = 0.5;
  /// The positions are averaged over bins this long (100 Hz: tremor at
  /// 8-12 Hz well below its Nyquist frequency, encoder steps averaged out).
  static constexpr double kBin_s = 0.01;
  /// The high-pass: the velocity less its centred mean over this many bins
  /// (90 ms): keeps 66 % of 8 Hz and 89 % of 10 Hz, 5 % of 2 Hz (an arm
  /// swinging back to neutral under a field) and nothing of a steady motion.
  static constexpr int kHighPassBins = 9;
  /// The high-passed velocity's RMS along its most moving axis must reach
  /// this: tremor of 0.1 mm at 8 Hz gives 2.3 mm/s; an encoder's one-count
  /// jitter (60 µm) averaged over a bin about 1.3 mm/s.
  static constexpr double kMinRms_mps = 2e-3;
  /// And it must change sign this often (each reversal past ±kMinRms_mps/2):
  /// tremor at 8-12 Hz reverses 16-24 times a second, an arm settling under
  /// a field (1-3 Hz) 2-6 times.
  static constexpr double kMinReversals_hz = 8.0;
};

/// What the newest HandMotionRule::kWindow_s of an arm's tracker says.
struct HandMotion {
  double span_s = 0.0;        ///< the history judged (short of the window: too early to tell)
  double rms_mps = 0.0;       ///< the high-passed velocity's RMS along its most moving axis
  double reversals_hz = 0.0;  ///< that velocity's sign reversals per second
  bool held = false;          ///< it moves as a held hand moves
};

/// Judges `samples` (oldest first, raw device units, as Hal::TrackerHistory
/// gives them; their calibration `arm`) by HandMotionRule. Allocates nothing.
HandMotion MeasureHandMotion(std::span<const haptics::TrackerSample> samples,
                             const ArmCalibration& arm);

/// What engagement asks of the interface a vehicle is driven with now.
struct InterfaceRest {
  /// The device's arms it reads (none: keys or a game controller).
  std::array<bool, haptics::kSides> hands{false, false};
  /// Each used hand's place for a zero intent (HandTargetsFor({})), m.
  std::array<std::optional<haptics::Vec3d>, haptics::kSides> neutral{};
  /// Its command is at rest now (AtRest).
  bool command_at_rest = true;
};

/// A command's every channel that moves the vehicle within this of zero.
constexpr double kCommandAtRest = 0.05;
bool AtRest(const TreadCommand& command);
/// The blimp's: power, helix, rudder, elevator and tail rotor (not its camera).
bool AtRest(const BlimpCommand& command);

/// The rest of an interface whose kind uses `hands`, from its zero-intent
/// `targets` and its command's `at_rest`.
InterfaceRest RestOf(const std::array<bool, haptics::kSides>& hands,
                     const interfaces::HandTargets& targets, bool at_rest);

/// Why the interface is not engaged.
enum class Disengaged {
  kNone,          ///< it is engaged
  kReleased,      ///< the device says nobody holds a used arm (its button or deadman is up)
  kNoHand,        ///< a used arm does not move as a held hand moves (or is lost)
  kOutOfReach,    ///< a used hand is farther than the reach from its neutral
  kNotAtNeutral,  ///< held again, but the command is not yet back at rest
};

/// "the device says nobody holds it", ...: for the progress log.
const char* ToString(Disengaged why);

class Engagement {
 public:
  /// How far a used hand may be from its neutral place: the farthest a held
  /// control's grip goes from its rest (the cockpit wheel's rim at its
  /// 135° stop: 2 · 0.12 m · sin 67.5° = 0.22 m), and a little more.
  static constexpr double kReach_m = 0.25;

  /// Engaged from the start when `engaged`; otherwise (the session's
  /// start) it engages once the hands are held at rest.
  explicit Engagement(bool engaged = false);

  /// One session tick: decides from `hal` (the device's presence, the
  /// tracker's history and the hands' positions) and the interface's
  /// `rest`. Returns engaged(). Allocates nothing.
  bool Update(const haptics::Hal& hal, const InterfaceRest& rest);

  bool engaged() const { return why_ == Disengaged::kNone; }
  Disengaged why() const { return why_; }
  /// The last motion judged of `side` (when the device did not say).
  const HandMotion& motion(haptics::Side side) const {
    return motion_[static_cast<size_t>(haptics::Index(side))];
  }
  /// The line the view shows while disengaged ("" engaged).
  const char* Line() const;

 private:
  /// Whether a person holds `side`, and why not.
  Disengaged Held(const haptics::Hal& hal, haptics::Side side);

  Disengaged why_;
  std::array<HandMotion, haptics::kSides> motion_{};
  std::vector<haptics::TrackerSample> history_;  ///< Hal::TrackerHistory's, reused
};

}  // namespace haptel::mediator
