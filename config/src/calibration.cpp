#include "haptel/config/calibration.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <system_error>

#include "haptel/config/check.hpp"
#include "yaml_map.hpp"

namespace haptel {

using config_detail::YamlMap;
namespace check = config_check;

namespace {

constexpr const char* kArmNames[2] = {"left", "right"};

// Plausibility ranges. They only catch garbage (a unit mix-up by orders of
// magnitude); the fit itself decides the values.
constexpr double kMaxTrackerScale = 1e3;   // m per device unit
constexpr double kMaxTrackerOffset = 1e3;  // m
constexpr double kMaxGloveGain = 1e3;      // rad per sensor count
constexpr double kMaxGloveOffset = 1e3;    // rad
constexpr double kMaxForceSlope = 1e4;     // N per device unit
constexpr double kMaxResidual = 1e4;       // N

template <size_t N>
std::array<double, N> ToArray(const std::vector<double>& values) {
  std::array<double, N> out{};
  for (size_t i = 0; i < N; ++i) out[i] = values[i];
  return out;
}

/// Every element finite, |v| <= max and (when `nonzero`) != 0; errors name the element.
template <size_t N>
void CheckList(const char* key, const std::array<double, N>& values, double max, bool nonzero) {
  for (size_t i = 0; i < N; ++i) {
    const double v = values[i];
    if (!(std::abs(v) <= max) || (nonzero && v == 0.0)) {
      check::Fail(std::string(key) + "[" + std::to_string(i) + "]",
                  std::string("a") + (nonzero ? " non-zero" : "") + " number in " +
                      check::Range(-max, max));
    }
  }
}

ArmCalibration ReadArm(YamlMap& arm) {
  ArmCalibration c;
  c.tracker_scale = ToArray<3>(arm.Numbers("tracker_scale", 3, "non-zero numbers"));
  c.tracker_offset = ToArray<3>(arm.Numbers("tracker_offset", 3));
  c.glove_gain = ToArray<kCalibrationGloveSensors>(
      arm.Numbers("glove_gain", kCalibrationGloveSensors, "non-zero numbers"));
  c.glove_offset =
      ToArray<kCalibrationGloveSensors>(arm.Numbers("glove_offset", kCalibrationGloveSensors));
  c.force_slope = ToArray<3>(arm.Numbers("force_slope", 3, "non-zero numbers"));
  c.force_residual = arm.RequireNumber("force_residual");
  c.finger_force_slope = arm.RequireNumber("finger_force_slope");
  arm.Finish();
  return c;
}

template <size_t N>
void EmitList(YAML::Emitter& out, const char* key, const std::array<double, N>& values,
              const char* comment) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (double v : values) out << v;
  out << YAML::EndSeq << YAML::Comment(comment);
}

}  // namespace

void ArmCalibration::ValidateOrThrow() const {
  CheckList("tracker_scale", tracker_scale, kMaxTrackerScale, true);
  CheckList("tracker_offset", tracker_offset, kMaxTrackerOffset, false);
  CheckList("glove_gain", glove_gain, kMaxGloveGain, true);
  CheckList("glove_offset", glove_offset, kMaxGloveOffset, false);
  CheckList("force_slope", force_slope, kMaxForceSlope, true);
  check::Number("force_residual", force_residual, 0.0, kMaxResidual);
  // Finger commands and forces are both >= 0: the slope must be positive.
  if (!(finger_force_slope > 0.0 && finger_force_slope <= kMaxForceSlope)) {
    check::Fail("finger_force_slope", "a positive number in (0, " +
                                          std::to_string(static_cast<int>(kMaxForceSlope)) + "]");
  }
}

void DeviceCalibration::ValidateOrThrow() const {
  for (int i = 0; i < 2; ++i) check::Nested(std::string("arms.") + kArmNames[i], arms[i]);
}

DeviceCalibration LoadCalibration(const std::filesystem::path& file) {
  YamlMap root = YamlMap::Load(file);
  DeviceCalibration d;
  d.file = file;
  d.device = root.RequireString("device");
  d.user = root.RequireString("user");
  if (!root.Has("arms")) root.Fail("arms", "a mapping with the 'left' and 'right' arms");
  YamlMap arms = root.Map("arms");
  for (int i = 0; i < 2; ++i) {
    if (!arms.Has(kArmNames[i])) {
      arms.Fail(kArmNames[i],
                std::string("the ") + kArmNames[i] + " arm's calibration (a mapping of keys)");
    }
    YamlMap arm = arms.Map(kArmNames[i]);
    d.arms[i] = ReadArm(arm);
  }
  arms.Finish();
  root.Finish();
  config_detail::ValidateIn(root, d);
  return d;
}

void SaveCalibration(const std::filesystem::path& file, const DeviceCalibration& calibration) {
  try {
    calibration.ValidateOrThrow();
  } catch (const ConfigFieldError& e) {
    throw ConfigError(file.string() + ": refusing to write an invalid calibration: " + e.what());
  }
  if (calibration.device.empty() || calibration.user.empty()) {
    throw ConfigError(file.string() +
                      ": refusing to write a calibration without a device and user name");
  }

  YAML::Emitter out;
  out.SetDoublePrecision(17);  // enough digits for every double to read back bit for bit
  out << YAML::Comment(
             "Haptel calibration, written by `haptel calibrate`; read by the device driver.\n"
             "tracker: metres = tracker_scale * raw + tracker_offset, per axis (x, y, z)\n"
             "glove: radians = glove_gain * counts + glove_offset, per sensor (22)\n"
             "force: newtons = force_slope * command, per axis; force_residual = RMS of that fit, "
             "N\n"
             "fingers: newtons = finger_force_slope * command")
      << YAML::Newline;
  out << YAML::BeginMap;
  out << YAML::Key << "device" << YAML::Value << calibration.device;
  out << YAML::Key << "user" << YAML::Value << calibration.user;
  out << YAML::Key << "arms" << YAML::Value << YAML::BeginMap;
  for (int i = 0; i < 2; ++i) {
    const ArmCalibration& c = calibration.arms[i];
    out << YAML::Key << kArmNames[i] << YAML::Value << YAML::BeginMap;
    EmitList(out, "tracker_scale", c.tracker_scale, "m per device unit");
    EmitList(out, "tracker_offset", c.tracker_offset, "m");
    EmitList(out, "glove_gain", c.glove_gain, "rad per count");
    EmitList(out, "glove_offset", c.glove_offset, "rad");
    EmitList(out, "force_slope", c.force_slope, "N per device unit");
    out << YAML::Key << "force_residual" << YAML::Value << c.force_residual
        << YAML::Comment("N (RMS)");
    out << YAML::Key << "finger_force_slope" << YAML::Value << c.finger_force_slope
        << YAML::Comment("N per device unit");
    out << YAML::EndMap;
  }
  out << YAML::EndMap << YAML::EndMap;
  if (!out.good())
    throw ConfigError(file.string() + ": cannot format the calibration: " + out.GetLastError());

  std::error_code ec;
  if (file.has_parent_path()) {
    std::filesystem::create_directories(file.parent_path(), ec);
    if (ec) {
      throw ConfigError(file.string() + ": cannot create folder " + file.parent_path().string() +
                        ": " + ec.message());
    }
  }
  // Write beside the target and rename: a reader never sees half a file.
  std::filesystem::path tmp = file;
  tmp += ".tmp";
  {
    std::ofstream stream(tmp, std::ios::trunc);
    stream << out.c_str() << "\n";
    stream.close();
    if (!stream) throw ConfigError(tmp.string() + ": cannot write the file");
  }
  std::filesystem::rename(tmp, file, ec);
  if (ec) {
    const std::string why = ec.message();
    std::filesystem::remove(tmp, ec);
    throw ConfigError(file.string() + ": cannot write the file: " + why);
  }
}

}  // namespace haptel
