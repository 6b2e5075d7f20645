#pragma once
/// @file The session's view part: the operator's view (a window, or
/// offscreen for the MP4), fed from the session's parts without blocking
/// them, with the person's keys and controller read in its window.
///
/// The view thread calls Fill at display rate: it reads the HAL and the
/// physics poses (seqlocks), the controls (the controls link's seqlock), the
/// decoded frame (a shared pointer taken under the receiver's short lock)
/// and the overlay and the predictive display's ghost the session loop
/// publishes (seqlocks). Nothing here waits on the servo loop, the physics
/// thread or the link.
#include <array>
#include <atomic>
#include <memory>
#include <vector>

#include "haptel/config/cockpit.hpp"
#include "haptel/config/physics.hpp"
#include "haptel/core/seqlock.hpp"
#include "haptel/haptics/hal.hpp"
#include "haptel/interfaces/input.hpp"
#include "haptel/mediator/interface_set.hpp"
#include "haptel/mediator/lap_timer.hpp"
#include "haptel/mediator/session.hpp"
#include "haptel/physics/cockpit_controls.hpp"
#include "haptel/video/frame.hpp"
#include "haptel/view/sdl_input.hpp"
#include "haptel/view/view.hpp"

namespace haptel::mediator {

struct SessionPhysics;
class ThirdPersonView;

class SessionView final : public view::ViewSource {
 public:
  /// What the view shows; everything must outlive the SessionView.
  struct Parts {
    const haptics::Hal* hal = nullptr;
    const SessionPhysics* physics = nullptr;  ///< null: no world (yet; SetPhysics): tracked hands
    const PhysicsConfig* physics_config = nullptr;
    const CockpitConfig* cockpit = nullptr;  ///< the controls' geometry, when there are controls
    physics::ControlsBodyConfig controls_bodies;  ///< as the world built them
    /// The vehicle's pictures (its VideoReceiver; null: no video).
    const video::FrameSource* video = nullptr;
    std::array<bool, 2> hands{false, true};  ///< tracked hands to draw without a world
    /// The track's map for the predictive display (null: prediction off, no map).
    std::shared_ptr<const view::TrackMap> map;
    /// The third-person view's pictures (null: none; a practice lap's, or
    /// haptel run --third-person).
    const ThirdPersonView* third_person = nullptr;
  };

  /// Opens the view (throws view::ViewError when it cannot) and reads the
  /// person's keys and controller into `input`.
  SessionView(const view::ViewOptions& options, const Parts& parts, interfaces::InputBox& input);
  /// A fleet's view (haptel run --fleet): one Parts per vehicle (at most
  /// view::Tiles::kMax), each vehicle's video on its tile, and the shown
  /// one's (Show) world, hands and video on the big screen.
  SessionView(const view::ViewOptions& options, std::vector<Parts> fleet,
              interfaces::InputBox& input);
  ~SessionView() override;

  /// Session thread: the overlay for the next frames (a seqlock store: never waits).
  void Publish(const view::Overlay& overlay) { overlay_.Store(overlay); }
  /// Session thread: where the head and the vehicle camera look (a tracked
  /// gaze turns the view and the screen; the robot's view never sets one).
  void Publish(const view::Gaze& gaze) { gaze_.Store(gaze); }
  /// Session thread: the predictive display's ghost, path and map poses
  /// (a seqlock store: never waits).
  void Publish(const view::Prediction& prediction) { prediction_.Store(prediction); }
  /// Session thread: a physics world built during the run (its proxy hands
  /// and controls are drawn from the next frame on). It must outlive the view.
  void SetPhysics(const SessionPhysics* physics) { SetPhysics(0, physics); }
  /// Session thread: the same for the fleet's vehicle `index`.
  void SetPhysics(int index, const SessionPhysics* physics) {
    physics_[static_cast<size_t>(index)].store(physics, std::memory_order_release);
  }
  /// Session thread: the fleet's vehicle whose parts are on the big screen
  /// from the next frame on (the driven one).
  void Show(int index) { shown_.store(index, std::memory_order_release); }
  /// Session thread: the fleet's tiles for the next frames (a seqlock
  /// store: never waits).
  void Publish(const view::Tiles& tiles) { tiles_.Store(tiles); }
  /// View thread.
  void Fill(view::ViewModel& model) override;
  view::ViewStats Stats() const;
  /// Stops the view (and finishes the MP4).
  void Stop();

 private:
  std::vector<Parts> parts_;  ///< one; or a fleet's, one per vehicle
  std::array<std::atomic<const SessionPhysics*>, view::Tiles::kMax> physics_{};
  std::atomic<int> shown_{0};
  Seqlock<view::Tiles> tiles_;
  Seqlock<view::Overlay> overlay_;
  Seqlock<view::Gaze> gaze_;
  Seqlock<view::Prediction> prediction_;
  view::SdlInput input_;
  std::unique_ptr<view::View> view_;  // last: its thread uses the rest
};

/// The view's options for `setup`'s run: window or offscreen, the MP4, the
/// title, and where the screen hangs.
view::ViewOptions ViewOptionsFor(const SessionSetup& setup);

/// Stops the view (finishing the MP4) and records its figures in `result`.
void StopAndRecord(SessionView& view, SessionResult& result);

/// The overlay's lines every vehicle's view has: the interface and operator,
/// the run and lap clocks, the time left, the gates and obstacles.
view::Overlay LapOverlay(const SessionSetup& setup, const char* interface_name, double t,
                         double lap_time_s, int gates_passed, int gates_total,
                         int obstacles_touched);

/// The overlay the view shows, from the session loop's state: the lap clock,
/// gates, the last contact, and the HUD exactly as the interface computed it
/// (the HUD cockpits' HudState; the gesture interface's speed and turn, as
/// the thesis kept them there). Builds it without allocating.
class OverlayFeed {
 public:
  OverlayFeed(const SessionSetup& setup, const Track& track);
  view::Overlay Make(double t, const LapTimer& lap, const InterfaceSet& interfaces,
                     const interfaces::VehicleFeedback& feedback, const TreadCommand& motors,
                     bool vehicle_up, bool touching);

 private:
  static constexpr double kHelpS = 15.0;  ///< how long an interface's help line shows
  const SessionSetup& setup_;
  int gates_total_;
  bool was_touching_ = false;
  char last_contact_[40] = "";
};

}  // namespace haptel::mediator
