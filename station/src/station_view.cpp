#include "haptel/station/station_view.hpp"

#include <cmath>
#include <cstdio>

namespace haptel::station {

namespace {
constexpr double kDegPerRad = 57.29577951308232;
}

view::Overlay StationOverlay(const std::string& camera, const std::string& person, double t_s,
                             const std::string& status, const std::string& message,
                             const std::string& vehicle) {
  view::Overlay o;
  std::snprintf(o.interface_name, sizeof o.interface_name, "station: %s", camera.c_str());
  std::snprintf(o.operator_name, sizeof o.operator_name, "%s", person.c_str());
  o.t_s = t_s;
  o.lap_time_s = -1.0;  // no lap: the control room has none
  if (vehicle.empty() || status.empty()) {
    std::snprintf(o.status, sizeof o.status, "%s",
                  status.empty() ? vehicle.c_str() : status.c_str());
    std::snprintf(o.message, sizeof o.message, "%s", message.c_str());
  } else {
    std::snprintf(o.status, sizeof o.status, "%s", vehicle.c_str());
    std::snprintf(o.message, sizeof o.message, "%s  %s", status.c_str(), message.c_str());
  }
  return o;
}

std::string VehicleText(const std::string& vehicle, const link::VehicleGlance& g) {
  if (g.seq == 0) return {};
  char text[96];
  const double heading_deg = std::fmod(std::fmod(g.heading * kDegPerRad, 360.0) + 360.0, 360.0);
  if (!g.pose_valid) {
    std::snprintf(text, sizeof text, "%s %.1f m/s", vehicle.c_str(), g.speed);
  } else if (g.flies) {
    std::snprintf(text, sizeof text, "%s x %+.1f y %+.1f alt %.1f m hdg %.0f %.1f m/s",
                  vehicle.c_str(), g.x, g.y, g.z, heading_deg, g.speed);
  } else {
    std::snprintf(text, sizeof text, "%s x %+.1f y %+.1f hdg %.0f %.1f m/s", vehicle.c_str(), g.x,
                  g.y, heading_deg, g.speed);
  }
  std::string line = text;
  if (g.failsafe) line += " failsafe";
  return line;
}

std::string StatusText(const CameraAim& applied) {
  char text[64];
  std::snprintf(text, sizeof text, "pan %+.1f tilt %+.1f zoom %.1fx", applied.pan * kDegPerRad,
                applied.tilt * kDegPerRad, applied.zoom);
  return text;
}

void StationView::Fill(view::ViewModel& model) {
  model.shapes.clear();
  model.video = video_.Latest();
  model.overlay = overlay_.Load();
}

}  // namespace haptel::station
