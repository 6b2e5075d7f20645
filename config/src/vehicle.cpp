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
  if (info->Uses(kRos2Section)) check::Nested("ros2", ros2);
  if (!reality.empty() && !info->simulated) {
    check::Fail("reality", "no reality for kind " + kind +
                               " (hardware has its own); only a simulated kind runs one");
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
    // One wheel velocity per speed level, whatever the kind (the section is
    // only validated for the kinds that use it).
    const size_t levels = static_cast<size_t>(std::max(1, v.drive.speed_levels));
    if (YamlMap can = root.Map("can");
        can.Has("level_turns_per_s") && v.can.level_turns_per_s.size() != levels) {
      can.Fail("level_turns_per_s", "a list of " + std::to_string(levels) + " wheel velocities");
    }
  });
}

}  // namespace haptel
