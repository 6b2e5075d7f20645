#include "haptel/mediator/session_view.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>

#include "haptel/interfaces/cockpit.hpp"
#include "haptel/mediator/session_physics.hpp"
#include "haptel/mediator/third_person_view.hpp"
#include "haptel/mediator/world_shapes.hpp"

namespace haptel::mediator {

SessionView::SessionView(const view::ViewOptions& options, const Parts& parts,
                         interfaces::InputBox& input)
    : SessionView(options, std::vector<Parts>{parts}, input) {}

SessionView::SessionView(const view::ViewOptions& options, std::vector<Parts> fleet,
                         interfaces::InputBox& input)
    : parts_(std::move(fleet)), input_(input) {
  if (parts_.empty() || parts_.size() > physics_.size()) {
    throw std::invalid_argument("session view: 1 to " + std::to_string(physics_.size()) +
                                " vehicles, not " + std::to_string(parts_.size()));
  }
  for (size_t i = 0; i < parts_.size(); ++i)
    physics_[i].store(parts_[i].physics, std::memory_order_relaxed);
  view_ = std::make_unique<view::View>(options, *this, &input_);
}

SessionView::~SessionView() { Stop(); }

void SessionView::Stop() {
  if (view_) view_->Stop();
}

view::ViewStats SessionView::Stats() const { return view_->Stats(); }

void SessionView::Fill(view::ViewModel& model) {
  const size_t shown = std::min(
      static_cast<size_t>(std::max(0, shown_.load(std::memory_order_acquire))), parts_.size() - 1);
  const Parts& part = parts_[shown];  // the big screen's: the driven vehicle's
  model.shapes.clear();
  model.overlay = overlay_.Load();
  model.gaze = gaze_.Load();
  model.prediction = prediction_.Load();
  model.map = part.map;
  model.tiles = tiles_.Load();
  for (int i = 0; i < model.tiles.count && i < static_cast<int>(parts_.size()); ++i) {
    const video::FrameSource* source = parts_[static_cast<size_t>(i)].video;
    model.tile_video[static_cast<size_t>(i)] =
        source != nullptr ? source->Latest() : video::Frame{};
  }
  // The hands: the proxies where a world moves them, the tracked hands otherwise.
  const SessionPhysics* physics = physics_[shown].load(std::memory_order_acquire);
  for (int i = 0; i < haptics::kSides; ++i) {
    const auto side = static_cast<haptics::Side>(i);
    const size_t first = model.shapes.size();
    const physics::HandPoses poses =
        physics != nullptr ? physics->world->Poses(side) : physics::HandPoses{};
    const haptics::HandSample sample = part.hal->LatestSample(side);
    if (poses.valid) {
      AppendProxyHand(model.shapes, poses, part.physics_config->hand, side);
    } else if (part.hands[i] && sample.valid) {
      AppendTrackedHand(model.shapes, sample, part.physics_config->hand);
    }
    // A device that bends the hand's motion (the mouse): the hand shakes
    // where it is drawn, and a ghost shows where the pointer alone puts it.
    if (const haptics::Hal::PseudoHaptics bent = part.hal->pseudo_haptics(side); bent.shown) {
      ShiftShapes(model.shapes, first, bent.report.shake);
      AppendPseudoHaptics(model.shapes, bent.report);
    }
    if (input_.force_arrows() && sample.valid && model.shapes.size() > first)
      AppendForceArrow(model.shapes, sample.position, sample.force);
  }
  // The wheel and lever only while the interface in use has them: a world
  // built for a cockpit stays when the person switches back to gesture.
  if (model.overlay.controls_shown && physics != nullptr && physics->port &&
      part.cockpit != nullptr) {
    AppendCockpit(model.shapes, *part.cockpit, part.controls_bodies, physics->port->Controls(),
                  model.overlay.contact_now);
  }
  for (int i = 0; i < haptics::kSides; ++i) {
    const haptics::ForceField field = part.hal->Setpoint(static_cast<haptics::Side>(i)).field;
    if (field.wall_active) AppendWall(model.shapes, field);
  }
  model.third_person = part.third_person != nullptr ? part.third_person->Latest() : video::Frame{};
  if (part.video != nullptr) model.video = part.video->Latest();
}

view::ViewOptions ViewOptionsFor(const SessionSetup& setup) {
  view::ViewOptions options;
  options.mode =
      setup.view == ViewKind::kWindow ? view::ViewMode::kWindow : view::ViewMode::kOffscreen;
  options.record = setup.record;
  options.title = setup.title.empty() ? "Haptel - " + setup.run.name : setup.title;
  if (setup.direct_view) options.screen = view::DirectViewScreen();
  options.stereo = {setup.run.view.stereo, setup.run.view.ipd_m};
  return options;
}

void StopAndRecord(SessionView& view, SessionResult& result) {
  view.Stop();  // finishes the MP4
  const view::ViewStats vs = view.Stats();
  RunRecord& rec = result.record;
  rec.view_fps = vs.fps;
  rec.view_frame_p99_ms = vs.frame_ms_p99;
  rec.video_to_screen_ms_p50 = vs.video_to_screen_ms_p50;
  rec.video_to_screen_ms_p99 = vs.video_to_screen_ms_p99;
  result.view_record_dropped = vs.record_dropped;
  result.view_record_error = vs.record_error;
}

view::Overlay LapOverlay(const SessionSetup& setup, const char* interface_name, double t,
                         double lap_time_s, int gates_passed, int gates_total,
                         int obstacles_touched) {
  view::Overlay o;
  std::snprintf(o.interface_name, sizeof o.interface_name, "%s", interface_name);
  std::snprintf(o.operator_name, sizeof o.operator_name, "%s", setup.operator_kind.c_str());
  o.t_s = t;
  o.lap_time_s = lap_time_s;
  o.time_left_s = setup.time_limit_s > 0 ? std::max(0.0, setup.time_limit_s - t) : -1.0;
  if (setup.lap_limit_s > 0) {
    // The lap limit counts the lap's clock, and the approach before the line.
    const double lap_left = std::max(0.0, setup.lap_limit_s - (lap_time_s > 0 ? lap_time_s : t));
    o.time_left_s = o.time_left_s < 0 ? lap_left : std::min(o.time_left_s, lap_left);
  }
  o.gates_passed = gates_passed;
  o.gates_total = gates_total;
  o.obstacles_touched = obstacles_touched;
  return o;
}

OverlayFeed::OverlayFeed(const SessionSetup& setup, const Track& track)
    : setup_(setup), gates_total_(static_cast<int>(track.gates().size())) {}

view::Overlay OverlayFeed::Make(double t, const LapTimer& lap, const InterfaceSet& interfaces,
                                const interfaces::VehicleFeedback& feedback,
                                const TreadCommand& motors, bool vehicle_up, bool touching) {
  const interfaces::MediatorInterface& current = interfaces.current();
  view::Overlay o = LapOverlay(setup_, current.name().c_str(), t, lap.lap_time_s(),
                               lap.gates_passed(), gates_total_, lap.obstacles_touched());
  if (touching && !was_touching_) {
    std::snprintf(last_contact_, sizeof last_contact_, "%s bumper at %.1f s",
                  feedback.bumper_left && feedback.bumper_right ? "front"
                  : feedback.bumper_left                        ? "left"
                                                                : "right",
                  t);
  }
  was_touching_ = touching;
  std::snprintf(o.last_contact, sizeof o.last_contact, "%s", last_contact_);
  o.contact_now = touching;
  o.speed_max_mps = setup_.vehicle.drive.max_speed;
  o.controls_shown = current.NeedsPhysics();
  if (const std::optional<interfaces::HudReading> hud = current.Hud(feedback, motors)) {
    o.hud = hud->shown;
    o.speed_mps = hud->speed_mps;
    o.turn_left = hud->turn_left;
    o.turn_right = hud->turn_right;
    o.throttle_locked = hud->throttle_locked;
  }
  if (const std::optional<interfaces::Guidance> guidance = current.CurrentGuidance()) {
    // What pushes the hand: shared control's force where the hand is now.
    o.guidance_shown = true;
    o.guidance_forward_n = guidance->force[0];
    o.guidance_left_n = guidance->force[1];
    o.guidance_max_n = std::max(guidance->max_force, 1e-6);
    o.guidance_ttc_s =
        std::isfinite(guidance->time_to_collision_s) ? guidance->time_to_collision_s : -1.0;
  }
  if (!vehicle_up) {
    std::snprintf(o.message, sizeof o.message, "waiting for vehicle '%s'",
                  setup_.vehicle.name.c_str());
  } else if (interfaces.switching()) {
    std::snprintf(o.message, sizeof o.message, "switching interface: hands off for a moment");
  } else if (const char* notice = current.Notice()) {
    std::snprintf(o.message, sizeof o.message, "%s", notice);
  } else if (const char* help = current.Help(!setup_.single_interface); help && t < kHelpS) {
    std::snprintf(o.message, sizeof o.message, "%s", help);
  }
  return o;
}

}  // namespace haptel::mediator
