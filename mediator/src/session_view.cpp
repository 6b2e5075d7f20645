#include "haptel/mediator/session_view.hpp"

#include "haptel/mediator/session_physics.hpp"
#include "haptel/mediator/video_receiver.hpp"
#include "haptel/mediator/world_shapes.hpp"

namespace haptel::mediator {

SessionView::SessionView(const view::ViewOptions& options, const Parts& parts,
                         interfaces::InputBox& input)
    : parts_(parts), input_(input) {
  view_ = std::make_unique<view::View>(options, *this, &input_);
}

SessionView::~SessionView() { Stop(); }

void SessionView::Stop() {
  if (view_) view_->Stop();
}

view::ViewStats SessionView::Stats() const { return view_->Stats(); }

void SessionView::Fill(view::ViewModel& model) {
  model.shapes.clear();
  model.overlay = overlay_.Load();
  // The hands: the proxies where a world moves them, the tracked hands otherwise.
  for (int i = 0; i < haptics::kSides; ++i) {
    const auto side = static_cast<haptics::Side>(i);
    if (parts_.physics != nullptr) {
      const physics::HandPoses poses = parts_.physics->world->Poses(side);
      if (poses.valid) {
        AppendProxyHand(model.shapes, poses, parts_.physics_config->hand, side);
        continue;
      }
    }
    if (parts_.hands[i]) {
      const haptics::HandSample sample = parts_.hal->LatestSample(side);
      if (sample.valid) AppendTrackedHand(model.shapes, sample, parts_.physics_config->hand);
    }
  }
  if (parts_.physics != nullptr && parts_.physics->port && parts_.cockpit != nullptr) {
    AppendCockpit(model.shapes, *parts_.cockpit, parts_.controls_bodies,
                  parts_.physics->port->Controls(), model.overlay.contact_now);
  }
  for (int i = 0; i < haptics::kSides; ++i) {
    const haptics::ForceField field = parts_.hal->Setpoint(static_cast<haptics::Side>(i)).field;
    if (field.wall_active) AppendWall(model.shapes, field);
  }
  if (parts_.video != nullptr) {
    const LatestFrame frame = parts_.video->Latest();
    model.video.image = frame.image;
    model.video.id = frame.id;
    model.video.capture_wall_ns = frame.capture_wall_ns;
  }
}

}  // namespace haptel::mediator
