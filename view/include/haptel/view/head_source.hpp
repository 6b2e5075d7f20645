#pragma once
/// @file The head that turns a pan/tilt camera (the blimp pilot's, thesis
/// 8.2: "the camera follows the pilot's head in pitch and yaw"): a head
/// pose from any source that gives one.
///
/// The session asks its HeadSource once a tick for the pose, from the
/// person's InputState, and hands it on as InputState::head_pan/head_tilt,
/// which the interfaces and the view already follow. Three sources:
///
/// - MouseHead: the mouse dragged in the window with the right button
///   (SdlInput's mouse-look), as before; Home looks ahead.
/// - GamepadHead: a game controller's right stick, in rate control: the
///   deflection past the dead zone turns the head at up to
///   HeadConfig::stick_rate_rad_s, and a released stick leaves it where it
///   looks. Position control would pull the look back to centre as soon as
///   the thumb let go (a self-centring stick's rest is its centre), so a
///   pilot could never keep watching a gate off to the side with his thumb
///   free. Clicking the right stick looks straight ahead again.
/// - OpenXR (openxr_head.cpp, MakeHeadSource): the view space's pose of an
///   OpenXR runtime's head-mounted display, read on a thread of its own.
///
/// A source that loses its tracker mid-run (the controller unplugged, the
/// OpenXR session lost) holds the last pose, so the camera stays still,
/// and says so in Notice(). Update() allocates nothing and never blocks.
#include <memory>
#include <string>

#include "haptel/config/run.hpp"
#include "haptel/interfaces/input.hpp"

namespace haptel::view {

struct HeadPose {
  double pan = 0.0;   ///< rad, positive left, within the pilot camera's range
  double tilt = 0.0;  ///< rad, positive up
};

class HeadSource {
 public:
  virtual ~HeadSource() = default;
  /// The head's pose at `t_s` (the session's clock), from what the person
  /// does now.
  virtual HeadPose Update(double t_s, const interfaces::InputState& person) = 0;
  /// One line for the person while something is wrong (no controller yet,
  /// the tracker lost); null when all is well.
  virtual const char* Notice() const { return nullptr; }
  /// Which source this is (after any fallback: the one that turns the head).
  virtual HeadSourceKind kind() const = 0;
};

/// The mouse-look SdlInput keeps in the InputState.
class MouseHead : public HeadSource {
 public:
  HeadPose Update(double, const interfaces::InputState& person) override {
    return {person.head_pan, person.head_tilt};
  }
  HeadSourceKind kind() const override { return HeadSourceKind::kMouse; }
};

/// The right stick of the person's game controller, in rate control.
class GamepadHead : public HeadSource {
 public:
  /// Controllers that went away before `at_start` are not this run's loss.
  GamepadHead(const HeadConfig& config, const interfaces::InputState& at_start);
  HeadPose Update(double t_s, const interfaces::InputState& person) override;
  const char* Notice() const override;
  HeadSourceKind kind() const override { return HeadSourceKind::kGamepad; }

  static constexpr const char* kNoControllerNotice =
      "no game controller for the head: plug one in to turn the camera";
  static constexpr const char* kLostNotice =
      "head tracker lost (the game controller went away): the camera holds still";

 private:
  HeadConfig config_;
  uint32_t disconnects_seen_;
  HeadPose pose_;
  double last_t_s_ = -1.0;
  bool recentre_held_ = false;
  bool connected_ = false;
  bool lost_ = false;
};

/// What MakeHeadSource made, and what the person is told of it.
struct MadeHeadSource {
  std::unique_ptr<HeadSource> source;
  /// The run asked for a source it cannot have (no OpenXR runtime): why,
  /// and what turns the head instead, as one line ("no OpenXR runtime
  /// (...): head follows the mouse"). Empty when it got what it asked.
  std::string fallback;
};

/// The source `config` names. OpenXR without a runtime (or one that cannot
/// run headless) falls back to the mouse and says why.
MadeHeadSource MakeHeadSource(const HeadConfig& config, const interfaces::InputState& at_start);

/// An OpenXR head pose, or null with `why_not` set (openxr_head.cpp).
std::unique_ptr<HeadSource> OpenOpenXrHead(std::string& why_not);

/// A head's forward direction in OpenXR's view space convention (x right,
/// y up, looking down -z) as pan and tilt, each clamped to the pilot
/// camera's range: what an HMD's orientation quaternion turns the camera to.
HeadPose HeadPoseOfOrientation(double qx, double qy, double qz, double qw);

}  // namespace haptel::view
