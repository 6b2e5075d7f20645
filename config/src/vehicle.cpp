#include "haptel/config/vehicle.hpp"

#include <algorithm>
#include <cctype>
#include <limits>

#include "airship_section.hpp"
#include "haptel/config/check.hpp"
#include "link_section.hpp"
#include "servo_section.hpp"
#include "yaml_map.hpp"

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

void TreadDriveConfig::ValidateOrThrow() const {
  check::Whole("speed_levels", speed_levels, 1, 1000);
  check::Number("max_speed", max_speed, 0.01, 10.0);
  check::Number("track_width", track_width, 0.02, 5.0);
  check::Number("motor_time_constant", motor_time_constant, 0.0, 5.0);
  check::Number("left_gain", left_gain, 0.5, 1.5);
  check::Number("right_gain", right_gain, 0.5, 1.5);
}

void BodyConfig::ValidateOrThrow() const {
  check::Number("radius", radius, 0.01, 5.0);
  check::Number("bumper_half_angle_deg", bumper_half_angle_deg, 1.0, 90.0);
  check::Number("bumper_both_deg", bumper_both_deg, 0.0, 45.0);
}

void RangeSensorConfig::ValidateOrThrow() const {
  check::Whole("beams", beams, 0, kMaxRangeBeams);
  check::Number("fov_deg", fov_deg, 0.0, 360.0);
  check::Number("max_range", max_range, 0.05, 50.0);
  check::Number("noise_sd", noise_sd, 0.0, 1.0);
}

void CameraConfig::ValidateOrThrow() const {
  if (source != CameraSourceKind::kSynthetic && source != CameraSourceKind::kDevice &&
      source != CameraSourceKind::kFile) {
    check::Fail("source", "one of: synthetic, device, file");
  }
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
  check::Number("rate_hz", rate_hz, 1.0, 120.0);
  check::Whole("width", width, 16, 4096);
  check::Whole("height", height, 16, 4096);
  check::Number("fov_deg", fov_deg, 10.0, 170.0);
  if (codec != CameraCodec::kJpeg && codec != CameraCodec::kH264)
    check::Fail("codec", "one of: jpeg, h264");
  check::Whole("jpeg_quality", jpeg_quality, 1, 100);
  check::Whole("bitrate_kbps", bitrate_kbps, 50, 50000);
  check::Number("mount_height", mount_height, 0.01, 5.0);
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
  check::Whole("domain_id", domain_id, 0, 232);
  const char* expected = "a ROS 2 topic name such as /cmd_vel (absolute; letters, digits, _ and /)";
  if (!IsRosTopicName(cmd_vel)) check::Fail("cmd_vel", expected);
  if (!IsRosTopicName(odom)) check::Fail("odom", expected);
  if (!image.empty() && !IsRosTopicName(image))
    check::Fail("image", std::string(expected) + ", or empty for none");
  if (!scan.empty() && !IsRosTopicName(scan))
    check::Fail("scan", std::string(expected) + ", or empty for none");
  check::Number("cmd_rate_hz", cmd_rate_hz, 1.0, 1000.0);
  check::Number("odom_timeout_s", odom_timeout_s, 0.05, 60.0);
}

void CanConfig::ValidateOrThrow(int levels) const {
  if (interface.empty() || interface.size() >= 16)
    check::Fail("interface", "a network interface name such as can0");
  check::Whole("left_node", left_node, 0, 63);
  check::Whole("right_node", right_node, 0, 63);
  check::Whole("io_node", io_node, 0, 63);
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
  check::Number("wheel_circumference", wheel_circumference, 0.01, 5.0);
  check::Number("command_rate_hz", command_rate_hz, 10.0, 1000.0);
  check::Number("heartbeat_period_s", heartbeat_period_s, 0.005, 2.0);
  check::Number("vel_ramp_rate", vel_ramp_rate, 0.1, 1000.0);
}

void VehicleConfig::ValidateOrThrow() const {
  if (const std::string problem = VehicleNameProblem(name); !problem.empty()) {
    check::Fail("name", problem);
  }
  const VehicleKindInfo* info = FindVehicleKind(kind);
  if (info == nullptr) check::Fail("kind", "one of: " + VehicleKindNames());
  check::Number("sim_rate_hz", sim_rate_hz, 50.0, 5000.0);
  check::Number("state_rate_hz", state_rate_hz, 1.0, 1000.0);
  check::Number("watchdog_timeout_s", watchdog_timeout_s, 0.01, 10.0);
  check::Nested("drive", drive);
  check::Nested("body", body);
  check::Nested("range_sensors", range_sensors);
  check::Nested("camera", camera);
  check::Nested("link", link);
  if (info->Uses(kCanSection)) {
    try {
      can.ValidateOrThrow(drive.speed_levels);
    } catch (const ConfigFieldError& e) {
      throw e.Within("can");
    }
  }
  if (info->Uses(kAirshipSection)) check::Nested("airship", airship);
  if (info->Uses(kServoSection)) check::Nested("servo", servo);
  if (info->Uses(kRos2Section)) check::Nested("ros2", ros2);
}

namespace {
/// Whether a known kind reads `section` (an unknown kind is refused later, by name).
bool UsesSection(const std::string& kind, VehicleSection section) {
  const VehicleKindInfo* info = FindVehicleKind(kind);
  return info != nullptr && info->Uses(section);
}
}  // namespace

VehicleConfig LoadVehicle(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  VehicleConfig v;
  v.file = file;
  v.name = root.RequireString("name");
  v.kind = root.String("kind", v.kind);
  if (root.Has("world")) {
    v.world = file.parent_path() / root.String("world", "");
  }
  v.sim_rate_hz = root.Number("sim_rate_hz", v.sim_rate_hz);
  v.state_rate_hz = root.Number("state_rate_hz", v.state_rate_hz);
  v.watchdog_timeout_s = root.Number("watchdog_timeout_s", v.watchdog_timeout_s);

  YamlMap drive = root.Map("drive");
  v.drive.speed_levels = drive.Integer("speed_levels", v.drive.speed_levels);
  v.drive.max_speed = drive.Number("max_speed", v.drive.max_speed);
  v.drive.track_width = drive.Number("track_width", v.drive.track_width);
  v.drive.motor_time_constant = drive.Number("motor_time_constant", v.drive.motor_time_constant);
  v.drive.left_gain = drive.Number("left_gain", v.drive.left_gain);
  v.drive.right_gain = drive.Number("right_gain", v.drive.right_gain);
  drive.Finish();

  YamlMap body = root.Map("body");
  v.body.radius = body.Number("radius", v.body.radius);
  v.body.bumper_half_angle_deg = body.Number("bumper_half_angle_deg", v.body.bumper_half_angle_deg);
  v.body.bumper_both_deg = body.Number("bumper_both_deg", v.body.bumper_both_deg);
  body.Finish();

  YamlMap ranges = root.Map("range_sensors");
  v.range_sensors.beams = ranges.Integer("beams", v.range_sensors.beams);
  v.range_sensors.fov_deg = ranges.Number("fov_deg", v.range_sensors.fov_deg);
  v.range_sensors.max_range = ranges.Number("max_range", v.range_sensors.max_range);
  v.range_sensors.noise_sd = ranges.Number("noise_sd", v.range_sensors.noise_sd);
  v.range_sensors.seed = static_cast<unsigned>(ranges.Integer(
      "seed", static_cast<int>(v.range_sensors.seed), 0, std::numeric_limits<int>::max()));
  ranges.Finish();

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
  if (camera.Has("device")) v.camera.device = camera.String("device", "");
  if (camera.Has("file")) v.camera.file = file.parent_path() / camera.String("file", "");
  v.camera.loop = camera.Bool("loop", v.camera.loop);
  v.camera.rate_hz = camera.Number("rate_hz", v.camera.rate_hz);
  v.camera.width = camera.Integer("width", v.camera.width);
  v.camera.height = camera.Integer("height", v.camera.height);
  v.camera.fov_deg = camera.Number("fov_deg", v.camera.fov_deg);
  const std::string codec = camera.String("codec", CameraCodecName(v.camera.codec));
  if (codec == "jpeg") {
    v.camera.codec = CameraCodec::kJpeg;
  } else if (codec == "h264") {
    v.camera.codec = CameraCodec::kH264;
  } else {
    camera.Fail("codec", "one of: jpeg, h264");
  }
  v.camera.jpeg_quality = camera.Integer("jpeg_quality", v.camera.jpeg_quality);
  v.camera.bitrate_kbps = camera.Integer("bitrate_kbps", v.camera.bitrate_kbps);
  v.camera.mount_height = camera.Number("mount_height", v.camera.mount_height);
  camera.Finish();

  YamlMap link = root.Map("link");
  v.link = config_detail::ReadLink(link, file.parent_path());
  if (root.Has("can")) {
    YamlMap can = root.Map("can");
    v.can.interface = can.String("interface", v.can.interface);
    v.can.left_node = can.Integer("left_node", v.can.left_node);
    v.can.right_node = can.Integer("right_node", v.can.right_node);
    v.can.io_node = can.Integer("io_node", v.can.io_node);
    v.can.right_reversed = can.Bool("right_reversed", v.can.right_reversed);
    if (can.Has("level_turns_per_s")) {
      v.can.level_turns_per_s =
          can.Numbers("level_turns_per_s", static_cast<size_t>(std::max(1, v.drive.speed_levels)),
                      "wheel velocities");
    }
    v.can.wheel_circumference = can.Number("wheel_circumference", v.can.wheel_circumference);
    v.can.command_rate_hz = can.Number("command_rate_hz", v.can.command_rate_hz);
    v.can.heartbeat_period_s = can.Number("heartbeat_period_s", v.can.heartbeat_period_s);
    v.can.vel_ramp_rate = can.Number("vel_ramp_rate", v.can.vel_ramp_rate);
    if (can.Has("log_dir")) v.can.log_dir = file.parent_path() / can.String("log_dir", "");
    can.Finish();
  } else if (UsesSection(v.kind, kCanSection)) {
    root.Fail("can", "a 'can' section for kind " + v.kind + " (its nodes and wheel velocities)");
  }
  if (root.Has("airship")) {
    YamlMap airship = root.Map("airship");
    v.airship = config_detail::ReadAirship(airship);
  } else if (UsesSection(v.kind, kAirshipSection)) {
    root.Fail("airship",
              "an 'airship' section for kind " + v.kind + " (its hull, fins and motors)");
  }
  if (root.Has("servo")) {
    YamlMap servo = root.Map("servo");
    v.servo = config_detail::ReadServoController(servo);
  } else if (UsesSection(v.kind, kServoSection)) {
    root.Fail("servo",
              "a 'servo' section for kind " + v.kind + " (its controller's protocol and channels)");
  }
  if (root.Has("ros2")) {
    YamlMap ros2 = root.Map("ros2");
    v.ros2.domain_id = ros2.Integer("domain_id", v.ros2.domain_id);
    v.ros2.cmd_vel = ros2.String("cmd_vel", v.ros2.cmd_vel);
    v.ros2.odom = ros2.String("odom", v.ros2.odom);
    v.ros2.image = ros2.String("image", v.ros2.image);
    v.ros2.scan = ros2.String("scan", v.ros2.scan);
    v.ros2.cmd_rate_hz = ros2.Number("cmd_rate_hz", v.ros2.cmd_rate_hz);
    v.ros2.odom_timeout_s = ros2.Number("odom_timeout_s", v.ros2.odom_timeout_s);
    ros2.Finish();
  }
  root.Finish();
  config_detail::ValidateIn(root, v);
  return v;
}

}  // namespace haptel
