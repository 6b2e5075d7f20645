#include "haptel/station/station_view.hpp"

#include <cmath>
#include <cstdio>

namespace haptel::station {

namespace {
constexpr double kDegPerRad = 57.29577951308232;
}

view::Overlay StationOverlay(const std::string& camera, const std::string& person, double t_s,
                             const std::string& status, const std::string& message) {
  view::Overlay o;
  std::snprintf(o.interface_name, sizeof o.interface_name, "station: %s", camera.c_str());
  std::snprintf(o.operator_name, sizeof o.operator_name, "%s", person.c_str());
  o.t_s = t_s;
  o.lap_time_s = -1.0;  // no lap: the control room has none
  std::snprintf(o.status, sizeof o.status, "%s", status.c_str());
  std::snprintf(o.message, sizeof o.message, "%s", message.c_str());
  return o;
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
