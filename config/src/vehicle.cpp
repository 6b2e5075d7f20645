#include "haptel/config/vehicle.hpp"

#include <cctype>

#include "link_section.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;

const char* CameraSourceName(CameraSourceKind kind) {
  switch (kind) {
    case CameraSourceKind::kSynthetic:
      return "synthetic";
    case CameraSourceKind::kDevice:
      return "device";
    case CameraSourceKind::kFile:
      return "file";
  }
  return "?";
}

std::string VehicleNameProblem(const std::string& name) {
  if (name.empty() || name.size() > kMaxVehicleNameLength) {
    return "a name of 1 to " + std::to_string(kMaxVehicleNameLength) +
           " characters (it is part of DDS topic names; this one has " +
           std::to_string(name.size()) + ")";
  }
  for (char ch : name) {
    if (!std::isalnum(static_cast<unsigned char>(ch)) && ch != '_' && ch != '-') {
      return "letters, digits, '_' or '-' only (it is part of DDS topic names)";
    }
  }
  return {};
}

VehicleConfig LoadVehicle(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  VehicleConfig v;
  v.file = file;
  v.name = root.RequireString("name");
  if (const std::string problem = VehicleNameProblem(v.name); !problem.empty()) {
    root.Fail("name", problem);
  }
  v.kind = root.String("kind", v.kind);
  if (v.kind != "sim-robot") root.Fail("kind", "one of: sim-robot");
  if (root.Has("world")) {
    v.world = file.parent_path() / root.String("world", "");
  }
  v.sim_rate_hz = root.Number("sim_rate_hz", v.sim_rate_hz, 50.0, 5000.0);
  v.state_rate_hz = root.Number("state_rate_hz", v.state_rate_hz, 1.0, 1000.0);
  v.watchdog_timeout_s = root.Number("watchdog_timeout_s", v.watchdog_timeout_s, 0.01, 10.0);

  YamlMap drive = root.Map("drive");
  v.drive.speed_levels = drive.Integer("speed_levels", v.drive.speed_levels, 1, 1000);
  v.drive.max_speed = drive.Number("max_speed", v.drive.max_speed, 0.01, 10.0);
  v.drive.track_width = drive.Number("track_width", v.drive.track_width, 0.02, 5.0);
  v.drive.motor_time_constant =
      drive.Number("motor_time_constant", v.drive.motor_time_constant, 0.0, 5.0);
  v.drive.left_gain = drive.Number("left_gain", v.drive.left_gain, 0.5, 1.5);
  v.drive.right_gain = drive.Number("right_gain", v.drive.right_gain, 0.5, 1.5);
  drive.Finish();

  YamlMap body = root.Map("body");
  v.body.radius = body.Number("radius", v.body.radius, 0.01, 5.0);
  v.body.bumper_half_angle_deg =
      body.Number("bumper_half_angle_deg", v.body.bumper_half_angle_deg, 1.0, 90.0);
  v.body.bumper_both_deg = body.Number("bumper_both_deg", v.body.bumper_both_deg, 0.0, 45.0);
  body.Finish();

  YamlMap camera = root.Map("camera");
  const std::string source = camera.String("source", CameraSourceName(v.camera.source));
  if (source == "synthetic") {
    v.camera.source = CameraSourceKind::kSynthetic;
  } else if (source == "device") {
    v.camera.source = CameraSourceKind::kDevice;
  } else if (source == "file") {
    v.camera.source = CameraSourceKind::kFile;
  } else {
    camera.Fail("source", "one of: synthetic, device, file");
  }
  // device and file may stay in the file while another source is chosen (to
  // switch back with one line), so they are read and checked whatever the source.
  if (camera.Has("device")) {
    v.camera.device = camera.String("device", "");
    const std::string& d = v.camera.device;
    const bool index = d.find_first_not_of("0123456789") == std::string::npos;
    if (!index && d.front() != '/') {
      camera.Fail("device", "a V4L2 device path such as /dev/video0, or a device index such as 0");
    }
    if (index && d.size() > 4) camera.Fail("device", "a device index in [0, 9999]");
  } else if (v.camera.source == CameraSourceKind::kDevice) {
    camera.Fail("device",
                "a V4L2 device path such as /dev/video0, or a device index, for source: device");
  }
  if (camera.Has("file")) {
    v.camera.file = file.parent_path() / camera.String("file", "");
  } else if (v.camera.source == CameraSourceKind::kFile) {
    camera.Fail("file", "a video file (relative to this file's folder) for source: file");
  }
  v.camera.loop = camera.Bool("loop", v.camera.loop);
  v.camera.rate_hz = camera.Number("rate_hz", v.camera.rate_hz, 1.0, 120.0);
  v.camera.width = camera.Integer("width", v.camera.width, 16, 4096);
  v.camera.height = camera.Integer("height", v.camera.height, 16, 4096);
  v.camera.fov_deg = camera.Number("fov_deg", v.camera.fov_deg, 10.0, 170.0);
  v.camera.jpeg_quality = camera.Integer("jpeg_quality", v.camera.jpeg_quality, 1, 100);
  v.camera.mount_height = camera.Number("mount_height", v.camera.mount_height, 0.01, 5.0);
  camera.Finish();

  YamlMap link = root.Map("link");
  v.link = config_detail::ReadLink(link);
  root.Finish();
  return v;
}

}  // namespace haptel
