#include "haptel/config/vehicle.hpp"

#include <algorithm>
#include <cctype>
#include <limits>

#include "haptel/config/archives.hpp"
#include "haptel/config/check.hpp"
#include "haptel/config/yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

const char* CameraCodecName(CameraCodec codec) {
  switch (codec) {
    case CameraCodec::kJpeg:
      return "jpeg";
    case CameraCodec::kH264:
      return "h264";
  }
  return "?";
}

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

void TreadDriveConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void BodyConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void RangeSensorConfig::ValidateOrThrow() const { config_detail::CheckFields(*this); }

void CameraConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  // device and file may be set while another source is chosen (to switch
  // back with one line), so a device set is checked whatever the source.
  if (!device.empty()) {
    const bool index = device.find_first_not_of("0123456789") == std::string::npos;
    if (!index && device.front() != '/') {
      check::Fail("device", "a V4L2 device path such as /dev/video0, or a device index such as 0");
    }
    if (index && device.size() > 4) check::Fail("device", "a device index in [0, 9999]");
  } else if (source == CameraSourceKind::kDevice) {
    check::Fail("device",
                "a V4L2 device path such as /dev/video0, or a device index, for source: device");
  }
  if (file.empty() && source == CameraSourceKind::kFile) {
    check::Fail("file", "a video file (relative to the config file's folder) for source: file");
  }
  if (name.empty() || name.size() > kMaxCameraNameLength ||
      name.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_-") != std::string::npos) {
    check::Fail("name",
                "a camera name of 1 to 31 lower-case letters, digits, '_' or '-' (it names the "
                "camera's DDS topics)");
  }
  if (pan_max_deg < pan_min_deg) check::Fail("pan_max_deg", "at least pan_min_deg");
  if (tilt_max_deg < tilt_min_deg) check::Fail("tilt_max_deg", "at least tilt_min_deg");
  const std::pair<const char*, const ServoChannelConfig*> servos[] = {
      {"pan_servo", &pan_servo}, {"tilt_servo", &tilt_servo}, {"zoom_servo", &zoom_servo}};
  for (const auto& [key, servo] : servos) {
    if (servo->channel >= 0) check::Nested(key, *servo);
  }
  if (pan_servo.channel >= 0 && !Range().pans())
    check::Fail("pan_servo",
                "no pan servo on a camera that does not pan (pan_min_deg < pan_max_deg)");
  if (tilt_servo.channel >= 0 && !Range().tilts())
    check::Fail("tilt_servo",
                "no tilt servo on a camera that does not tilt (tilt_min_deg < tilt_max_deg)");
  if (zoom_servo.channel >= 0 && !Range().zooms())
    check::Fail("zoom_servo", "no zoom servo on a camera that does not zoom (zoom_max > 1)");
}

CameraRange CameraConfig::Range() const {
  constexpr double kRadPerDeg = 0.017453292519943295;
  return {pan_min_deg * kRadPerDeg, pan_max_deg * kRadPerDeg, tilt_min_deg * kRadPerDeg,
          tilt_max_deg * kRadPerDeg, zoom_max};
}

std::vector<CameraConfig> VehicleConfig::Cameras() const {
  std::vector<CameraConfig> all{camera};
  all.insert(all.end(), extra_cameras.begin(), extra_cameras.end());
  return all;
}

namespace {
/// A ROS 2 topic name: absolute, of letters, digits, '_' and '/' tokens
/// that do not start with a digit (ROS 2's rules, without ~ and {}).
bool IsRosTopicName(const std::string& name) {
  if (name.size() < 2 || name[0] != '/' || name.back() == '/') return false;
  bool token_start = true;
  for (size_t i = 1; i < name.size(); ++i) {
    const char c = name[i];
    if (c == '/') {
      if (token_start) return false;  // "//"
      token_start = true;
      continue;
    }
    const bool ok = std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
    if (!ok || (token_start && std::isdigit(static_cast<unsigned char>(c)) != 0)) return false;
    token_start = false;
  }
  return true;
}
}  // namespace

std::string Ros2DdsTopic(const std::string& ros_name) { return "rt" + ros_name; }

void Ros2Config::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  const char* expected = "a ROS 2 topic name such as /cmd_vel (absolute; letters, digits, _ and /)";
  if (!IsRosTopicName(cmd_vel)) check::Fail("cmd_vel", expected);
  if (!IsRosTopicName(odom)) check::Fail("odom", expected);
  if (!image.empty() && !IsRosTopicName(image))
    check::Fail("image", std::string(expected) + ", or empty for none");
  if (!scan.empty() && !IsRosTopicName(scan))
    check::Fail("scan", std::string(expected) + ", or empty for none");
}

void CanConfig::ValidateOrThrow(int levels) const {
  config_detail::CheckFields(*this);
  if (interface.empty() || interface.size() >= 16)
    check::Fail("interface", "a network interface name such as can0");
  if (right_node == left_node) check::Fail("right_node", "a node id other than left_node's");
  if (io_node == left_node || io_node == right_node)
    check::Fail("io_node", "a node id other than the wheels'");
  if (static_cast<int>(level_turns_per_s.size()) != levels) {
    check::Fail("level_turns_per_s",
                "one velocity per speed level: " + std::to_string(levels) + " numbers");
  }
  for (size_t i = 0; i < level_turns_per_s.size(); ++i) {
    const double previous = i == 0 ? 0.0 : level_turns_per_s[i - 1];
    const std::string key = "level_turns_per_s[" + std::to_string(i) + "]";
    check::Number(key, level_turns_per_s[i], 1e-3, 100.0);
    if (level_turns_per_s[i] <= previous) check::Fail(key, "more than the level below");
  }
}

void VehicleConfig::ValidateOrThrow() const {
  config_detail::CheckFields(*this);
  if (const std::string problem = VehicleNameProblem(name); !problem.empty()) {
    check::Fail("name", problem);
  }
  const VehicleKindInfo* info = FindVehicleKind(kind);
  if (info == nullptr) check::Fail("kind", "one of: " + VehicleKindNames());
  if (info->Uses(kCanSection)) {
    try {
      can.ValidateOrThrow(drive.speed_levels);
    } catch (const ConfigFieldError& e) {
      throw e.Within("can");
    }
  }
  if (info->Uses(kAirshipSection)) check::Nested("airship", airship);
  if (info->Uses(kServoSection)) check::Nested("servo", servo);
  ValidateCameras();
  if (info->Uses(kRos2Section)) check::Nested("ros2", ros2);
  if (!reality.empty() && !info->simulated) {
    check::Fail("reality", "no reality for kind " + kind +
                               " (hardware has its own); only a simulated kind runs one");
  }
}

ServoControllerConfig VehicleConfig::ServoWithCameras() const {
  ServoControllerConfig out = servo;
  out.camera_channels.clear();
  const std::vector<CameraConfig> cameras = Cameras();
  for (size_t i = 0; i < cameras.size(); ++i) {
    const CameraConfig& c = cameras[i];
    const CameraRange r = c.Range();
    using Axis = CameraServoChannel::Axis;
    const auto add = [&](const ServoChannelConfig& s, Axis axis, double lo, double hi) {
      if (s.channel >= 0) out.camera_channels.push_back({s, static_cast<int>(i), axis, lo, hi});
    };
    add(c.pan_servo, Axis::kPan, r.pan_min, r.pan_max);
    add(c.tilt_servo, Axis::kTilt, r.tilt_min, r.tilt_max);
    add(c.zoom_servo, Axis::kZoom, 1.0, r.zoom_max);
  }
  return out;
}

void VehicleConfig::ValidateCameras() const {
  const std::vector<CameraConfig> cameras = Cameras();
  if (cameras.size() > static_cast<size_t>(kMaxVehicleCameras)) {
    check::Fail("cameras", "at most " + std::to_string(kMaxVehicleCameras) + " cameras");
  }
  const auto key = [&](size_t i) {
    return cameras_listed ? "cameras[" + std::to_string(i) + "]" : std::string("camera");
  };
  const VehicleKindInfo* info = FindVehicleKind(kind);
  const bool servo_kind = info != nullptr && info->Uses(kServoSection);
  // Each output once: the seven channels' and every camera axis's.
  std::vector<int> outputs;
  if (servo_kind) {
    for (const ServoChannelConfig& c : servo.channels) outputs.push_back(c.channel);
  }
  const int outputs_max =
      servo.protocol == ServoProtocol::kSc8000 ? kSc8000Channels : kMaestroChannels;
  for (size_t i = 0; i < cameras.size(); ++i) {
    const CameraConfig& c = cameras[i];
    check::Nested(key(i), c);
    for (size_t j = 0; j < i; ++j) {
      if (cameras[j].name == c.name) {
        check::Fail(key(i) + ".name", "a name no other camera of the vehicle has ('" + c.name +
                                          "' appears twice: their topics would be one)");
      }
    }
    const std::pair<const char*, const ServoChannelConfig*> servos[] = {
        {"pan_servo", &c.pan_servo}, {"tilt_servo", &c.tilt_servo}, {"zoom_servo", &c.zoom_servo}};
    for (const auto& [axis, s] : servos) {
      if (s->channel < 0) continue;
      const std::string at = key(i) + "." + axis + ".channel";
      if (i == 0) {
        check::Fail(key(i) + "." + axis,
                    "no servo on the driven camera (it turns through the driving command's "
                    "servo.channels.camera_pan and camera_tilt)");
      }
      if (!servo_kind) {
        check::Fail(key(i) + "." + axis, "no servo for kind " + kind +
                                             " (only a kind with a servo controller drives one)");
      }
      if (s->channel >= outputs_max) {
        check::Fail(at, std::string("an output the ") + ServoProtocolName(servo.protocol) +
                            " has: 0.." + std::to_string(outputs_max - 1) + " (" +
                            std::to_string(s->channel) + " is not one of its outputs)");
      }
      if (servo.protocol == ServoProtocol::kSc8000 &&
          (s->min_us < kSc8000MinPulse_us || s->max_us > kSc8000MaxPulse_us)) {
        check::Fail(key(i) + "." + axis, "pulses within the SC-8000's 800..2200 us");
      }
      for (int used : outputs) {
        if (used == s->channel) {
          check::Fail(at,
                      "an output no other channel uses (" + std::to_string(used) + " is taken)");
        }
      }
      outputs.push_back(s->channel);
    }
  }
}

namespace {
/// Whether a known kind reads `section` (an unknown kind is refused later, by name).
bool UsesSection(const std::string& kind, VehicleSection section) {
  const VehicleKindInfo* info = FindVehicleKind(kind);
  return info != nullptr && info->Uses(section);
}
}  // namespace

VehicleConfig LoadVehicle(const std::filesystem::path& file) {
  return config_detail::LoadFile<VehicleConfig>(file, [](YamlMap& root, VehicleConfig& v) {
    const auto require = [&](const char* section, VehicleSection used, const char* what) {
      if (!root.Has(section) && UsesSection(v.kind, used)) {
        root.Fail(section, std::string("a '") + section + "' section for kind " + v.kind + " (" +
                               what + ")");
      }
    };
    require("can", kCanSection, "its nodes and wheel velocities");
    require("airship", kAirshipSection, "its hull, fins and motors");
    require("servo", kServoSection, "its controller's protocol and channels");
    // One camera (`camera:`, named pilot unless it says otherwise) or a
    // list of them (`cameras:`, the driven one first); not both.
    if (root.Has("cameras")) {
      if (root.Has("camera")) {
        root.Fail("cameras",
                  "either 'camera:' (one camera) or 'cameras:' (a list, the driven camera "
                  "first), not both: move the 'camera:' mapping into the list as its first item");
      }
      std::vector<YamlMap> list = root.MapList("cameras");
      if (list.empty() || list.size() > static_cast<size_t>(kMaxVehicleCameras)) {
        root.Fail("cameras", "a list of 1 to " + std::to_string(kMaxVehicleCameras) +
                                 " cameras, each a mapping such as {name: pilot, fov_deg: 90}");
      }
      v.cameras_listed = true;
      for (size_t i = 0; i < list.size(); ++i) {
        CameraConfig c = config_detail::ReadSection<CameraConfig>(list[i], v.file.parent_path());
        if (i == 0) {
          v.camera = std::move(c);
        } else {
          // Not the driven camera: named by the file, or by its place.
          if (!list[i].Has("name")) c.name = "camera" + std::to_string(i + 1);
          if (!list[i].Has("priority")) c.priority = static_cast<int>(i);
          v.extra_cameras.push_back(std::move(c));
        }
      }
    }
    // One wheel velocity per speed level, whatever the kind (the section is
    // only validated for the kinds that use it).
    const size_t levels = static_cast<size_t>(std::max(1, v.drive.speed_levels));
    if (YamlMap can = root.Map("can");
        can.Has("level_turns_per_s") && v.can.level_turns_per_s.size() != levels) {
      can.Fail("level_turns_per_s", "a list of " + std::to_string(levels) + " wheel velocities");
    }
  });
}

std::string CameraNames(const VehicleConfig& vehicle) {
  std::string names = vehicle.camera.name;
  for (const CameraConfig& c : vehicle.extra_cameras) names += "," + c.name;
  return names;
}

std::string KeepOnlyCameras(VehicleConfig& vehicle, const std::vector<std::string>& names) {
  std::vector<CameraConfig> kept;
  bool driven = false;
  for (size_t i = 0; i < names.size(); ++i) {
    if (std::find(names.begin(), names.begin() + static_cast<std::ptrdiff_t>(i), names[i]) !=
        names.begin() + static_cast<std::ptrdiff_t>(i))
      return "camera '" + names[i] + "' named twice";
    if (names[i] == vehicle.camera.name) {
      driven = true;
      continue;
    }
    const auto found = std::find_if(vehicle.extra_cameras.begin(), vehicle.extra_cameras.end(),
                                    [&](const CameraConfig& c) { return c.name == names[i]; });
    if (found == vehicle.extra_cameras.end()) {
      return "vehicle '" + vehicle.file.string() + "' has no camera '" + names[i] +
             "'; expected some of " + CameraNames(vehicle);
    }
    kept.push_back(*found);
  }
  if (!driven) {
    return "the driven camera '" + vehicle.camera.name +
           "' must stream (the pilot flies by its picture); expected it among " +
           CameraNames(vehicle);
  }
  vehicle.extra_cameras = std::move(kept);
  return "";
}

}  // namespace haptel
