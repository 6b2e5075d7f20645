#pragma once
/// @file The control room's screen: the camera's picture filling the view
/// (the direct view's screen: nothing in front of it), and over it the
/// station's lines — the camera, where it points and how far it zooms, who
/// holds it, what to press. A ViewSource: the view thread reads the latest
/// picture (a shared pointer taken under the receiver's short lock) and the
/// overlay the station's loop publishes (a seqlock); nothing waits.
#include <string>

#include "haptel/core/seqlock.hpp"
#include "haptel/link/families.hpp"
#include "haptel/station/camera_station.hpp"
#include "haptel/video/frame.hpp"
#include "haptel/view/view.hpp"

namespace haptel::station {

/// The station's overlay: its name and person, the clock, the camera's
/// status line (StatusText) and one message (the holder's line, or what to
/// press). With the vehicle's line (VehicleText; empty: no state yet) that
/// line is the overlay's status (the vehicle's own line) and the camera's
/// leads the message. No lap: lap_time_s is negative (view::OverlayLines
/// draws no lap, gates or contacts then).
view::Overlay StationOverlay(const std::string& camera, const std::string& person, double t_s,
                             const std::string& status, const std::string& message,
                             const std::string& vehicle = {});

/// "blimp1 x +12.3 y -4.5 alt 3.2 m hdg 270 2.1 m/s" (m, degrees
/// counter-clockwise from +x, m/s over the ground; alt for a vehicle that
/// flies): where `vehicle` is and how it moves, as its last state says;
/// " failsafe" appended while its watchdog holds it (no fresh driving
/// command). Empty before any state.
std::string VehicleText(const std::string& vehicle, const link::VehicleGlance& glance);

/// "pan +12.0 tilt -5.0 zoom 3.0x" (degrees): where the camera points now,
/// as the vehicle applied it; short enough for the overlay's panel.
std::string StatusText(const CameraAim& applied);

/// What the person can do, for the message line.
inline constexpr const char* kStationHelp =
    "drag: pan/tilt  wheel, PgUp/PgDn: zoom  space: home  Esc: end";

class StationView final : public view::ViewSource {
 public:
  /// The view's frames show `video`'s pictures; both must outlive this.
  explicit StationView(const video::FrameSource& video) : video_(video) {}
  /// Any thread: the overlay for the next frames.
  void Publish(const view::Overlay& overlay) { overlay_.Store(overlay); }
  /// View thread.
  void Fill(view::ViewModel& model) override;

 private:
  const video::FrameSource& video_;
  Seqlock<view::Overlay> overlay_;
};

}  // namespace haptel::station
